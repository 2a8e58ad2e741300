#!/usr/bin/env bash
# The cost of a ray across surfaces (issue 36, item 4): renders each surface of a corpus — the
# ordinary presets and gallery surfaces, and equations whose rays have nearly multiple roots or
# huge cancellation ("cliffs") — as the explorer's equation mode shows it (its default camera,
# lights and colours), SIZE×SIZE, one sample per pixel, one thread, RUNS times, and prints per
# surface the median render time (as `kardia render` reports it: without starting and loading)
# and its pixels/s, then the corpus's median pixels/s and the slowest surface's ratio to it.
# Target: the slowest surface within 10× of the median. Usage:
#
#   bench/cliffs.sh [RUNS] [SIZE] [BINARY]
#     RUNS    renders of each surface (default 3; the median is reported)
#     SIZE    image side in pixels (default 100)
#     BINARY  the kardia binary (default: target/release/kardia, built with cargo first)
#
# Set KEEP=DIR to keep the scenes and images in DIR; ONLY=REGEX renders only the surfaces
# whose name matches. COARSE=1 times the explorer's coarse frame instead: 1/8 of an 800×600
# view (100×75, SIZE ignored), one shadow ray a light (the spherical light's SAMPLES dropped,
# as the explorer's live passes take one), the whole command's wall time (start, scene load
# with its surface's load-time work, render, PNG) as "median s" (target: under 0.1 s).
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-3}
SIZE=${2:-100}
BIN=${3:-}
if [ -z "$BIN" ]; then
  cargo build --release -q
  BIN=target/release/kardia
fi
dir=${KEEP:-$(mktemp -d)}
mkdir -p "$dir"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$dir"' EXIT

# name | surface as IMPLICIT takes it | scale | BOUND ("" for a preset's own)
corpus() {
  cat <<'LIST'
heart|heart|1|
taubin_heart|taubin_heart|1|
torus|torus 1 0.3|1|
kummer|kummer 1.140175425|0.5|
barth_sextic|barth_sextic|0.55|
clebsch|clebsch|0.25|
chmutov6|chmutov 6|0.6|
sphere16|"(x^2+y^2+z^2)^8 = 1"|1|1.5
cayley|"4*(x^2 + y^2 + z^2) + 16*x*y*z - 1"|0.9|1.6
roman|"x^2*y^2 + y^2*z^2 + z^2*x^2 - x*y*z"|2.2|1
dingdong|"x^2 + y^2 + z^3 - z^2"|0.8|1.6
sphere|"x^2 + y^2 + z^2 - 1"|1|2
chmutov12|chmutov 12|0.6|
chmutov16|chmutov 16|0.6|
sphere16_off|"((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1"|1|2
line4|"(x+y+z+1)^4 - 1"|1|2
line8|"(x+y+z+1)^8 - 1"|1|2
line16|"(x+y+z+1)^16 - 1"|1|2
plane16|"(x+y+z)^16 - 1"|1|2
shells8|"(x^2+y^2+z^2-1)^8 - 1e-5"|1|2
tube8|"(x^2+y^2-1)^8 - 1e-12"|1|2
LIST
}

samples=" SAMPLES 4"
width=$SIZE
height=$SIZE
if [ -n "${COARSE:-}" ]; then
  samples=""
  width=100
  height=75
fi

scene() { # SURFACE SCALE BOUND
  local bound=""
  [ -n "$3" ] && bound=" BOUND $3"
  cat <<SCENE
CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32
BACKGROUND (0.03, 0.03, 0.05)
AMBIENT (0.06, 0.06, 0.07)
LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6$samples
LIGHT (3, 6, 1) (0.25, 0.25, 0.3)
IMPLICIT $1 (0, 0, 0) ($2, 0, 0) (0, $2, 0) (0, 0, $2) (0.7454, 0.0319, 0.0802) SPECULAR 0.4 60 INSIDE (0.8714, 0.6308, 0.117)$bound
SCENE
}

results=()
printf '%-14s %12s %14s\n' surface "median s" "pixels/s"
while IFS='|' read -r name surface scale bound; do
  if [ -n "${ONLY:-}" ] && ! [[ $name =~ $ONLY ]]; then continue; fi
  scene "$surface" "$scale" "$bound" >"$dir/$name.scene"
  times=()
  for _ in $(seq 1 "$RUNS"); do
    # The render's time from its summary line ("…, T s, R rays, X k rays/s → …"): R / X,
    # which has two or three significant digits where T (two decimals) may have none.
    if [ -n "${COARSE:-}" ]; then
      start=$(date +%s.%N)
      "$BIN" render "$dir/$name.scene" -o "$dir/$name.png" --width "$width" --height "$height" \
        --spp 1 --threads 1 >/dev/null 2>&1
      times+=("$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.6f", b - a }')")
      continue
    fi
    line=$("$BIN" render "$dir/$name.scene" -o "$dir/$name.png" --width "$width" \
      --height "$height" --spp 1 --threads 1 2>&1 | grep ' spp, ' | tail -n 1)
    times+=("$(sed -E 's/.*, ([0-9]+) rays, ([0-9.]+) ?([kM]?) rays\/s.*/\1 \2 \3/' <<<"$line" |
      awk '{ r = $2 * ($3 == "M" ? 1e6 : ($3 == "k" ? 1e3 : 1)); printf "%.6f", $1 / r }')")
  done
  median=$(printf '%s\n' "${times[@]}" | sort -g | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }')
  pps=$(awk -v t="$median" -v n="$((width * height))" 'BEGIN { printf "%.0f", n / (t > 0 ? t : 0.001) }')
  printf '%-14s %12s %14s\n' "$name" "$median" "$pps"
  results+=("$name $pps")
done < <(corpus)
printf '%s\n' "${results[@]}" | sort -k2,2g | awk '
  { name[NR] = $1; pps[NR] = $2 }
  END {
    median = (NR % 2) ? pps[(NR + 1) / 2] : (pps[NR / 2] + pps[NR / 2 + 1]) / 2
    printf "median %.0f pixels/s over %d surfaces; slowest %s at %.0f pixels/s: median/slowest %.1f× (target ≤ 10×)\n",
      median, NR, name[1], pps[1], median / pps[1]
  }'
