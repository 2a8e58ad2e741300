#!/usr/bin/env bash
# Renders the same heart with POV-Ray 3.7 (polynomial + sturm) and with kardia, side by side,
# and prints a table of median whole-process wall times, ratios, rays per second and peak
# memory. Usage:
#
#   bench/compare.sh [RUNS] [SIZE]        (defaults: 5 runs, 1600×1600)
#
# Installs povray, GNU time and (if needed) the release build. Each configuration runs RUNS
# times, interleaved with the others so machine noise hits all alike; the median is reported.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-5}
SIZE=${2:-1600}
THREADS=$(nproc)

need() { command -v "$1" >/dev/null 2>&1; }
apt_install() {
  local sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}
need povray || apt_install povray
[ -x /usr/bin/time ] || apt_install time

cargo build --release --quiet --bin kardia --example imgcompare
KARDIA=target/release/kardia
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run NAME CMD…: one timed run; appends "wall_s peak_kib rays" to $work/NAME.
run() {
  local name=$1; shift
  local log="$work/$name.log"
  /usr/bin/time -f "TIME %e %M" "$@" >"$log" 2>&1 || { cat "$log" >&2; exit 1; }
  local wall peak rays
  wall=$(awk '/^TIME/ {print $2}' "$log")
  peak=$(awk '/^TIME/ {print $3}' "$log")
  rays=$(rays_of "$name" "$log")
  echo "$wall $peak $rays" >>"$work/$name"
}

# Rays traced, as each renderer reports them: POV-Ray's camera rays plus shadow-ray tests;
# kardia's summary line ("… N rays …").
rays_of() {
  case $1 in
    pov*) tr '\r' '\n' <"$2" | awk '/^Rays:/ {r=$2} /^Shadow Ray Tests:/ {s=$4} END {print r+s}' ;;
    *) tr '\r' '\n' <"$2" | sed -n 's/.* \([0-9][0-9]*\) rays.*/\1/p' | tail -n 1 ;;
  esac
}

pov() { # pov THREADS OUT
  povray +Ibench/heart.pov +O"$2" +W"$SIZE" +H"$SIZE" +WT"$1" -D +FN -GA
}
kardia() { # kardia THREADS SOLVER OUT
  "$KARDIA" render bench/heart.scene -o "$3" --width "$SIZE" --height "$SIZE" --spp 1 \
    --threads "$1" --solver "$2"
}

SOLVERS=$("$KARDIA" render --help | sed -n 's/.*possible values: \(.*\)\]/\1/p' | tr -d ',' | head -n 1)
[ -n "$SOLVERS" ] || SOLVERS="sturm"

for i in $(seq "$RUNS"); do
  echo "run $i of $RUNS…" >&2
  run pov-1 pov 1 "$work/pov.png"
  for s in $SOLVERS; do run "kardia-$s-1" kardia 1 "$s" "$work/kardia-$s.png"; done
  run "pov-$THREADS" pov "$THREADS" "$work/pov.png"
  for s in $SOLVERS; do run "kardia-$s-$THREADS" kardia "$THREADS" "$s" "$work/kardia-$s.png"; done
done

median() { sort -n | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
col() { awk -v c="$2" '{print $c}' "$work/$1" | median; }

printf '\n%s×%s heart with shadows, %s runs each, median whole-process wall time\n\n' "$SIZE" "$SIZE" "$RUNS"
printf '| renderer | threads | wall time (s) | POV-Ray time / this | rays/s | peak memory (MiB) |\n'
printf '|---|---|---|---|---|---|\n'
for t in 1 "$THREADS"; do
  base=$(col "pov-$t" 1)
  for name in "pov-$t" $(for s in $SOLVERS; do echo "kardia-$s-$t"; done); do
    wall=$(col "$name" 1); peak=$(col "$name" 2); rays=$(col "$name" 3)
    label=${name%-*}; label=${label/pov/POV-Ray 3.7 (sturm)}; label=${label/kardia-/kardia --solver }
    awk -v l="$label" -v t="$t" -v w="$wall" -v b="$base" -v r="$rays" -v p="$peak" \
      'BEGIN {printf "| %s | %s | %.2f | %.2f× | %.2f M | %.0f |\n", l, t, w, b/w, r/w/1e6, p/1024}'
  done
done
for s in $SOLVERS; do
  k1=$(col "kardia-$s-1" 1); kn=$(col "kardia-$s-$THREADS" 1)
  awk -v s="$s" -v a="$k1" -v b="$kn" -v t="$THREADS" \
    'BEGIN {printf "\nkardia --solver %s: %s threads are %.2f× faster than 1\n", s, t, a/b}'
done

echo
echo "Same framing and specks (last renders):"
for s in $SOLVERS; do
  target/release/examples/imgcompare "$work/pov.png" "$work/kardia-$s.png"
done
