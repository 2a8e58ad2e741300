#!/usr/bin/env bash
# Renders the same heart with POV-Ray 3.7 (polynomial + sturm) and with kardia (every
# solver), one thread and then all threads, and prints a table of median whole-process wall
# times, ratios, rays per second and peak memory; then checks the targets of issue 13 and that
# both renderers cover the same pixels. Usage:
#
#   bench/compare.sh [RUNS] [SIZE] [typed]   (defaults: 5 runs, 1600×1600)
#
# With `typed` as third argument it compares the typed surfaces instead (torus, Barth's
# sextic, Chmutov's octic, Taubin's heart, each clipped to a ball): kardia's IMPLICIT against
# POV-Ray's `polynomial … sturm` with the same monomials (from kardia's own expansion, by the
# povpoly example), clipped_by the same sphere, one thread, same camera and light.
#
# Installs what it needs with apt-get (povray, GNU time) and builds the release binaries.
# Each configuration runs RUNS times, interleaved with the others so that machine noise hits
# all alike; medians are reported. Set KEEP=DIR to keep the last images and logs in DIR.
# Exit status: 0 when the silhouettes agree (the timing targets are reported, not enforced).
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-5}
SIZE=${2:-1600}
THREADS=$(nproc)

apt_install() {
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "installing $* with apt-get…" >&2
  $sudo apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}
command -v povray >/dev/null 2>&1 || apt_install povray
[ -x /usr/bin/time ] || apt_install time

cargo build --release --quiet --bin kardia --example imgcompare --example povpoly
KARDIA=target/release/kardia
IMGCOMPARE=target/release/examples/imgcompare
if [ -n "${KEEP:-}" ]; then
  work=$KEEP
  mkdir -p "$work"
  rm -f "$work"/*.times
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

# The command lines (arrays, so that /usr/bin/time runs the renderer itself).
pov_cmd() { # THREADS OUT
  cmd=(povray +Ibench/heart.pov +O"$2" +W"$SIZE" +H"$SIZE" +WT"$1" -D -V +FN)
}
kardia_cmd() { # THREADS SOLVER OUT [SEED]
  cmd=("$KARDIA" render bench/heart.scene -o "$3" --width "$SIZE" --height "$SIZE" --spp 1
    --threads "$1" --solver "$2" --seed "${4:-0}")
}

# Rays traced, as each renderer reports them: POV-Ray's camera rays plus its shadow-ray
# tests (from its render statistics); kardia's summary line ("… N rays …": primary + shadow).
rays_of() { # NAME LOG
  case $1 in
    pov*) tr '\r' '\n' <"$2" | awk '/^Rays:/ {r = $2} /^Shadow Ray Tests:/ {s = $4} END {print r + s}' ;;
    *) tr '\r' '\n' <"$2" | sed -n 's/.* \([0-9][0-9]*\) rays.*/\1/p' | tail -n 1 ;;
  esac
}

# timed NAME: runs "${cmd[@]}" once under GNU time; appends "wall_s peak_kib rays cpu_s" to
# $work/NAME.times. The wall time is read from the nanosecond clock around the run (GNU
# time's %e counts hundredths of a second: 2 % of a 0.5 s render); GNU time gives the peak
# memory and CPU time. The renderer's own output (POV-Ray's progress and statistics,
# kardia's summary) goes to $work/NAME.log.
timed() {
  local name=$1 log="$work/$1.log" tf="$work/$1.time" start end
  start=$(date +%s%N)
  if ! /usr/bin/time -f "%M %U %S" -o "$tf" "${cmd[@]}" >"$log" 2>&1; then
    echo "failed: ${cmd[*]}" >&2
    tail -n 20 "$log" >&2
    exit 1
  fi
  end=$(date +%s%N)
  read -r peak user sys <"$tf"
  echo "$(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.4f", (b - a) / 1e9}') $peak $(rays_of "$name" "$log") $(awk -v u="$user" -v s="$sys" 'BEGIN {print u + s}')" >>"$work/$name.times"
}


median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
col() { awk -v c="$2" '{print $c}' "$work/$1.times" | median; }

# The typed surfaces: name | preset and parameters | clip radius | uniform scale | camera.
TYPED_SURFACES=(
  "torus|torus 1 0.3|1.4|1|(4.2, 0.5, 2.6)"
  "barth_sextic|barth_sextic|2|0.6|(4.5, 1.2, 0.9)"
  "chmutov8|chmutov 8|1.8|0.7|(4.5, 1.2, 0.9)"
  "taubin_heart|taubin_heart|1.5|1|(4.5, 1.2, 0.6)"
)

# Writes $work/NAME.scene and $work/NAME.pov for one TYPED_SURFACES entry: the same picture
# (kardia's (x, y, z) is POV-Ray's <x, z, y>), one point light with shadows, black background.
typed_files() { # ENTRY
  local name preset bound scale cam
  IFS='|' read -r name preset bound scale cam <<<"$1"
  local c=${cam//[() ]/}
  local cx cy cz
  IFS=, read -r cx cy cz <<<"$c"
  cat >"$work/$name.scene" <<SCENE
SIZE $SIZE $SIZE
CAMERA $cam (0, 0, 0) (0, 0, 1) 35
BACKGROUND (0, 0, 0)
AMBIENT (0.1, 0.1, 0.1)
LIGHT (5, -3, 4) (1, 1, 1)
IMPLICIT $preset (0, 0, 0) ($scale, 0, 0) (0, $scale, 0) (0, 0, $scale) (0.8, 0.1, 0.1) SPECULAR 0.4 40 BOUND $bound
SCENE
  # shellcheck disable=SC2086
  local poly
  poly=$("$POVPOLY" $preset)
  cat >"$work/$name.pov" <<POV
#version 3.7;
global_settings { assumed_gamma 1.0 ambient_light rgb 1 }
background { rgb 0 }
camera {
  perspective
  location <$cx, $cz, $cy>
  look_at <0, 0, 0>
  sky <0, 1, 0>
  right x * image_width / image_height
  angle 35
}
light_source { <5, 4, -3> color rgb 1 }
polynomial {
  $poly
  sturm
  clipped_by { sphere { <0, 0, 0>, $bound } }
  bounded_by { sphere { <0, 0, 0>, $bound } }
  texture {
    pigment { rgb <0.8, 0.1, 0.1> }
    finish { ambient 0.1 diffuse 1 phong 0.4 phong_size 40 }
  }
  scale $scale
}
POV
}

typed_main() {
  POVPOLY=target/release/examples/povpoly
  local entry name
  for entry in "${TYPED_SURFACES[@]}"; do typed_files "$entry"; done
  echo "$(povray --version 2>&1 | grep -m1 '^POV-Ray') | kardia $(git describe --always --dirty 2>/dev/null || echo '?')" >&2
  for i in $(seq "$RUNS"); do
    echo "run $i of $RUNS…" >&2
    for entry in "${TYPED_SURFACES[@]}"; do
      name=${entry%%|*}
      cmd=(povray +I"$work/$name.pov" +O"$work/pov-$name.png" +W"$SIZE" +H"$SIZE" +WT1 -D -V +FN)
      timed "pov-$name"
      cmd=("$KARDIA" render "$work/$name.scene" -o "$work/kardia-$name.png" --spp 1 --threads 1 --seed 0)
      timed "kardia-$name"
    done
  done
  printf '\n%s×%s typed surfaces clipped to a ball, one light with shadows, 1 sample per pixel,\n' "$SIZE" "$SIZE"
  printf 'one thread, %s runs each, medians of whole-process wall time, CPU time, peak memory\n\n' "$RUNS"
  printf '| surface | POV-Ray wall (s) | kardia wall (s) | POV-Ray time / kardia | POV-Ray CPU (s) | kardia CPU (s) | by CPU time | peak memory POV-Ray / kardia (MiB) | same framing |\n'
  printf '|---|---|---|---|---|---|---|---|---|\n'
  local status=0
  for entry in "${TYPED_SURFACES[@]}"; do
    name=${entry%%|*}
    "$KARDIA" render "$work/$name.scene" -o "$work/kardia-$name-seed1.png" --spp 1 --seed 1 --quiet
    local noise out differ pov_area k_area framing
    noise=$("$IMGCOMPARE" "$work/kardia-$name.png" "$work/kardia-$name-seed1.png" | sed -n 's/^silhouettes differ on \([0-9]*\) pixels.*/\1/p')
    out=$("$IMGCOMPARE" "$work/pov-$name.png" "$work/kardia-$name.png")
    pov_area=$(echo "$out" | sed -n '1s/.*: \([0-9]*\) object pixels.*/\1/p')
    k_area=$(echo "$out" | sed -n '2s/.*: \([0-9]*\) object pixels.*/\1/p')
    differ=$(echo "$out" | sed -n 's/^silhouettes differ on \([0-9]*\) pixels.*/\1/p')
    if awk -v d="$differ" -v n="$noise" -v a="$pov_area" -v b="$k_area" \
      'BEGIN {e = (a > b) ? a - b : b - a; exit !(a > 0 && d <= n && e <= 0.002 * a)}'; then
      framing="PASS ($differ differ, jitter noise $noise)"
    else
      framing="FAIL ($differ differ, jitter noise $noise; areas $pov_area, $k_area)"
      status=1
    fi
    awk -v l="$name" -v pw="$(col "pov-$name" 1)" -v kw="$(col "kardia-$name" 1)" \
      -v pc="$(col "pov-$name" 4)" -v kc="$(col "kardia-$name" 4)" \
      -v pm="$(col "pov-$name" 2)" -v km="$(col "kardia-$name" 2)" -v f="$framing" \
      'BEGIN {cpu = (kc > 0) ? sprintf("%.2f×", pc / kc) : "–"; printf "| %s | %.3f | %.3f | %.2f× | %.2f | %.2f | %s | %.1f / %.1f | %s |\n", l, pw, kw, pw / kw, pc, kc, cpu, pm / 1024, km / 1024, f}'
  done
  echo
  echo "Target (issue 13): each typed surface ≥ 15× POV-Ray on one thread (reported, not enforced)."
  echo "POV-Ray's wall time includes its front end's start-up and polling sleeps (a 16×16 render"
  echo "takes about 0.7 s wall for 0.02 s CPU): the wall-time ratio falls as the image grows."
  return $status
}

[ "${3:-}" = typed ] && { typed_main; exit $?; }

SOLVERS=$("$KARDIA" render --help | sed -n 's/.*\[default: \([a-z]*\)\].*possible values: \([a-z, ]*\)\].*/\1 \2/p' | head -n 1 | tr -d ',')
DEFAULT=${SOLVERS%% *}
SOLVERS=$(echo "$SOLVERS" | tr ' ' '\n' | awk 'NF && !seen[$0]++' | tr '\n' ' ')
[ -n "$DEFAULT" ] || { echo "cannot read the solvers from kardia render --help" >&2; exit 1; }
THREAD_COUNTS=1
[ "$THREADS" -gt 1 ] && THREAD_COUNTS="1 $THREADS"

echo "$(povray --version 2>&1 | grep -m1 '^POV-Ray') | kardia $(git describe --always --dirty 2>/dev/null || echo '?')" >&2
echo "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $THREADS threads" >&2
for i in $(seq "$RUNS"); do
  echo "run $i of $RUNS…" >&2
  for t in $THREAD_COUNTS; do
    pov_cmd "$t" "$work/pov.png"
    timed "pov-$t"
    for s in $SOLVERS; do
      kardia_cmd "$t" "$s" "$work/kardia-$s.png"
      timed "kardia-$s-$t"
    done
  done
done


printf '\n%s×%s heart with shadows, 1 sample per pixel, %s runs each, medians of whole-process\n' "$SIZE" "$SIZE" "$RUNS"
printf 'wall time (nanosecond clock), CPU time (GNU time %%U + %%S) and peak resident memory (%%M)\n\n'
printf '| renderer | threads | wall time (s) | POV-Ray time / this | CPU time (s) | rays | rays/s | peak memory (MiB) |\n'
printf '|---|---|---|---|---|---|---|---|\n'
for t in $THREAD_COUNTS; do
  base=$(col "pov-$t" 1)
  for name in "pov-$t" $(for s in $SOLVERS; do echo "kardia-$s-$t"; done); do
    case $name in
      pov*) label="POV-Ray 3.7 (sturm)" ;;
      *) s=${name#kardia-}; s=${s%-*}; label="kardia --solver $s"; [ "$s" = "$DEFAULT" ] && label="$label (default)" ;;
    esac
    awk -v l="$label" -v t="$t" -v w="$(col "$name" 1)" -v b="$base" -v r="$(col "$name" 3)" \
      -v p="$(col "$name" 2)" -v c="$(col "$name" 4)" \
      'BEGIN {printf "| %s | %s | %.3f | %.2f× | %.2f | %.2f M | %.2f M | %.1f |\n", l, t, w, b / w, c, r / 1e6, r / w / 1e6, p / 1024}'
  done
done

# The targets of issue 13 (reported, not enforced: timings depend on the machine).
verdict() { awk -v x="$1" -v goal="$2" 'BEGIN {print (x >= goal) ? "met" : "NOT met"}'; }
echo
echo "Targets (single thread unless stated):"
pov1=$(col pov-1 1)
for s in $SOLVERS; do
  k1=$(col "kardia-$s-1" 1)
  r=$(awk -v a="$pov1" -v b="$k1" 'BEGIN {printf "%.2f", a / b}')
  if [ "$s" = "$DEFAULT" ]; then
    echo "  default solver ($s) ≥ 12× faster than POV-Ray: ${r}× — $(verdict "$r" 12)"
  fi
  if [ "$s" = sturm ]; then
    echo "  --solver sturm no slower than POV-Ray: ${r}× — $(verdict "$r" 1)"
  fi
done
if [ "$THREADS" -gt 1 ]; then
  for s in $SOLVERS; do
    r=$(awk -v a="$(col "kardia-$s-1" 1)" -v b="$(col "kardia-$s-$THREADS" 1)" 'BEGIN {printf "%.2f", a / b}')
    goal=$(awk -v t="$THREADS" 'BEGIN {print 0.925 * t}')
    echo "  kardia --solver $s, $THREADS threads ≥ ${goal}× faster than 1: ${r}× — $(verdict "$r" "$goal")"
  done
  r=$(awk -v a="$pov1" -v b="$(col "pov-$THREADS" 1)" 'BEGIN {printf "%.2f", a / b}')
  echo "  (POV-Ray, $THREADS threads against 1: ${r}×)"
fi

# Same framing: kardia jitters its one sample inside each pixel where POV-Ray takes the
# centre, so edge pixels disagree at random along the whole outline. Two kardia renders with
# different seeds measure that noise; a framing off by half a pixel or more would make POV-Ray
# and kardia disagree on more pixels than that (about half the outline instead of a quarter
# to a third), and on the silhouette's area.
echo
echo "Same framing (the last renders; object = more than 8 levels from the black background):"
"$KARDIA" render bench/heart.scene -o "$work/kardia-seed1.png" --width "$SIZE" --height "$SIZE" \
  --spp 1 --seed 1 --quiet
status=0
noise=$("$IMGCOMPARE" "$work/kardia-$DEFAULT.png" "$work/kardia-seed1.png" | sed -n 's/^silhouettes differ on \([0-9]*\) pixels.*/\1/p')
echo "  kardia seed 0 against seed 1 (the jitter noise): $noise pixels differ"
for s in $SOLVERS; do
  out=$("$IMGCOMPARE" "$work/pov.png" "$work/kardia-$s.png")
  echo "$out" | sed 's/^/  /; s#'"$work"'/##g'
  pov_area=$(echo "$out" | sed -n '1s/.*: \([0-9]*\) object pixels.*/\1/p')
  k_area=$(echo "$out" | sed -n '2s/.*: \([0-9]*\) object pixels.*/\1/p')
  differ=$(echo "$out" | sed -n 's/^silhouettes differ on \([0-9]*\) pixels.*/\1/p')
  if awk -v d="$differ" -v n="$noise" -v a="$pov_area" -v b="$k_area" \
    'BEGIN {e = (a > b) ? a - b : b - a; exit !(a > 0 && d <= n && e <= 0.002 * a)}'; then
    echo "  PASS: POV-Ray and kardia --solver $s cover the same pixels ($differ differ, within the jitter noise of $noise; areas within 0.2%)"
  else
    echo "  FAIL: POV-Ray and kardia --solver $s do not cover the same pixels ($differ differ, jitter noise $noise; areas $pov_area and $k_area)"
    status=1
  fi
done
exit $status
