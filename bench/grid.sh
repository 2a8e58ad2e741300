#!/usr/bin/env bash
# Scenes of many objects: the paper's heart in a grid of placed HEARTs, each filling its cell,
# seen face on, rendered by kardia (the grid written with REPEAT) and by POV-Ray 3.7
# (`polynomial {6, …} sturm` with a tight `bounded_by`, the grid written with #for), one
# thread, one sample per pixel, SIZE×SIZE; every grid covers the same square of the image, so
# one heart is the grid of 1×1. Prints a table of median whole-process wall times of
# interleaved runs, the ratios, peak memory; then the large grid (kardia only) with its load
# time, render time and peak memory per object. Usage:
#
#   bench/grid.sh [RUNS] [SIZE] [SIDES] [BIG]
#     RUNS   runs of each configuration (default 5)
#     SIZE   image side in pixels (default 600)
#     SIDES  grid sides to compare, quoted (default "1 10 32 64": 1, 100, 1 024, 4 096 hearts)
#     BIG    "COLSxROWS" of the large grid, kardia only (default 400x250: 100 000 hearts;
#            "none" skips it)
#
# Installs what it needs with apt-get (povray, GNU time) and builds the release binary. Set
# KEEP=DIR to keep the scenes, images and logs in DIR. The targets of issue 36 are reported,
# not enforced.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-5}
SIZE=${2:-600}
SIDES=${3:-"1 10 32 64"}
BIG=${4:-400x250}

apt_install() {
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "installing $* with apt-get…" >&2
  $sudo apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}
command -v povray >/dev/null 2>&1 || apt_install povray
[ -x /usr/bin/time ] || apt_install time

cargo build --release --quiet --bin kardia
KARDIA=target/release/kardia
if [ -n "${KEEP:-}" ]; then
  work=$KEEP
  mkdir -p "$work"
  rm -f "$work"/*.times
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

# The grid covers a square of side 2.3 centred on the origin in the plane x = 0 (the unit
# heart's width and height, about); the camera on +x sees it with a margin. A heart of scale
# a spans y in ±1.14a and z in [−1.01a, 1.24a]: a = cell / 2.3 leaves a thin gap, and its
# position sits 0.115a below the cell's centre so the heart is centred in it.
# kardia's (x, y, z) is POV-Ray's <x, z, y> (the mirror makes both images the same picture).
write_scenes() { # NAME COLS ROWS
  local name=$1 cols=$2 rows=$3 side
  side=$((cols > rows ? cols : rows))
  cat >"$work/$name.scene" <<SCENE
SIZE $SIZE $SIZE
CAMERA (10, 0, 0) (0, 0, 0) (0, 0, 1) 15
BACKGROUND (0, 0, 0)
AMBIENT (0.1, 0.1, 0.1)
LIGHT (10, -6, 8) (1, 1, 1)
MATERIAL red (0.8, 0.1, 0.1) SPECULAR 0.4 40
LET cell = 2.3 / $side
LET a = cell / 2.3
REPEAT i FROM 0 TO $((rows - 1))
  REPEAT j FROM 0 TO $((cols - 1))
    HEART (0, (j - ($cols - 1) / 2) * cell, (i - ($rows - 1) / 2) * cell - 0.115 * a) (a, 0, 0) (0, a, 0) (0, 0, a) red
  END
END
SCENE
  cat >"$work/$name.pov" <<POV
#version 3.7;
global_settings { assumed_gamma 1.0 ambient_light rgb 1 }
background { rgb 0 }
camera {
  perspective
  location <10, 0, 0>
  look_at <0, 0, 0>
  sky <0, 1, 0>
  right x * image_width / image_height
  angle 15
}
light_source { <10, 8, -6> color rgb 1 }
#declare Heart = polynomial {
  6,
  xyz(6,0,0): 8, xyz(4,2,0): 12, xyz(4,0,2): 12, xyz(4,0,0): -12,
  xyz(2,4,0): 6, xyz(2,3,0): -0.1, xyz(2,2,2): 12, xyz(2,2,0): -12,
  xyz(2,0,4): 6, xyz(2,0,2): -12, xyz(2,0,0): 6,
  xyz(0,6,0): 1, xyz(0,4,2): 3, xyz(0,4,0): -3, xyz(0,3,2): -1,
  xyz(0,2,4): 3, xyz(0,2,2): -6, xyz(0,2,0): 3,
  xyz(0,0,6): 1, xyz(0,0,4): -3, xyz(0,0,2): 3, xyz(0,0,0): -1
  sturm
  bounded_by { box { <-0.72, -1.01, -1.14>, <0.72, 1.24, 1.14> } }
  texture {
    pigment { rgb <0.8, 0.1, 0.1> }
    finish { ambient 0.1 diffuse 1 phong 0.4 phong_size 40 }
  }
}
#declare Cell = 2.3 / $side;
#declare A = Cell / 2.3;
#for (I, 0, $((rows - 1)))
  #for (J, 0, $((cols - 1)))
    object { Heart scale A translate <0, (I - ($rows - 1) / 2) * Cell - 0.115 * A, (J - ($cols - 1) / 2) * Cell> }
  #end
#end
POV
}

# timed NAME: runs "${cmd[@]}" once under GNU time; appends "wall_s peak_kib" to
# $work/NAME.times (wall time from the nanosecond clock around the run, peak memory from GNU
# time); the renderer's output goes to $work/NAME.log.
timed() {
  local name=$1 log="$work/$1.log" tf="$work/$1.time" start end
  start=$(date +%s%N)
  if ! /usr/bin/time -f "%M" -o "$tf" "${cmd[@]}" >"$log" 2>&1; then
    echo "failed: ${cmd[*]}" >&2
    tail -n 20 "$log" >&2
    exit 1
  fi
  end=$(date +%s%N)
  echo "$(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.4f", (b - a) / 1e9}') $(cat "$tf")" >>"$work/$name.times"
}
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
col() { awk -v c="$2" '{print $c}' "$work/$1.times" | median; }
pov_cmd() { cmd=(povray +I"$work/$1.pov" +O"$work/pov-$1.png" +W"$SIZE" +H"$SIZE" +WT1 -D -V +FN); }
kardia_cmd() { cmd=("$KARDIA" render "$work/$1.scene" -o "$work/kardia-$1.png" --spp 1 --threads 1 --seed 0); }

for n in $SIDES; do write_scenes "grid$n" "$n" "$n"; done
echo "$(povray --version 2>&1 | grep -m1 '^POV-Ray') | kardia $(git describe --always --dirty 2>/dev/null || echo '?')" >&2
for i in $(seq "$RUNS"); do
  echo "run $i of $RUNS…" >&2
  for n in $SIDES; do
    pov_cmd "grid$n"
    timed "pov-grid$n"
    kardia_cmd "grid$n"
    timed "kardia-grid$n"
  done
done

first=${SIDES%% *}
printf '\n%s×%s, one thread, 1 sample per pixel, %s interleaved runs, medians of whole-process wall time\n\n' "$SIZE" "$SIZE" "$RUNS"
printf '| hearts | kardia (s) | POV-Ray (s) | POV-Ray / kardia | kardia / kardia at %s | peak memory kardia / POV-Ray (MiB) |\n' "$((first * first))"
printf '|---|---|---|---|---|---|\n'
for n in $SIDES; do
  awk -v h="$((n * n))" -v k="$(col "kardia-grid$n" 1)" -v p="$(col "pov-grid$n" 1)" \
    -v k1="$(col "kardia-grid$first" 1)" -v km="$(col "kardia-grid$n" 2)" -v pm="$(col "pov-grid$n" 2)" \
    'BEGIN {printf "| %d | %.3f | %.3f | %.1f× | %.2f× | %.1f / %.1f |\n", h, k, p, p / k, k / k1, km / 1024, pm / 1024}'
done
echo
echo "Targets (issue 36): 4 096 hearts ≥ 10× POV-Ray; 4 096 hearts within 3× of one heart."

[ "$BIG" = none ] && exit 0
cols=${BIG%x*}
rows=${BIG#*x}
objects=$((cols * rows))
write_scenes big "$cols" "$rows"
# Load time: the same scene rendered at one pixel (its load, one ray and the process);
# render time: the full render less that.
for i in $(seq "$RUNS"); do
  cmd=("$KARDIA" render "$work/big.scene" -o "$work/big-1px.png" --width 1 --height 1 --spp 1 --threads 1)
  timed big-load
  kardia_cmd big
  timed big
done
printf '\n%s placed hearts (%s×%s), %s×%s, one thread, %s runs, medians\n\n' "$objects" "$cols" "$rows" "$SIZE" "$SIZE" "$RUNS"
printf '| load (s) | load + render (s) | render (s) | peak memory (MiB) | per object (bytes) |\n|---|---|---|---|---|\n'
awk -v l="$(col big-load 1)" -v t="$(col big 1)" -v m="$(col big 2)" -v n="$objects" \
  'BEGIN {printf "| %.3f | %.3f | %.3f | %.1f | %.0f |\n", l, t, t - l, m / 1024, m * 1024 / n}'
