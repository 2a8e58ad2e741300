#!/usr/bin/env bash
# Compares two kardia binaries on one scene by alternating pairs of whole-process wall times:
# each pair runs both (the order swaps from pair to pair, so that drift hits both alike) and
# gives the ratio NEW / BASE; the median of the ratios is printed last. On a shared machine
# this is steadier than any absolute time. Usage:
#
#   bench/pairs.sh PAIRS BASE_BINARY NEW_BINARY SCENE SIZE [THREADS]
#
# One sample per pixel, SIZE×SIZE, THREADS threads (default 1). To get a base binary, build
# an older commit in a worktree: `git worktree add ../base REV && (cd ../base && cargo build
# --release)`.
set -euo pipefail
if [ $# -lt 5 ]; then
  sed -n '2,11p' "$0" >&2
  exit 2
fi
PAIRS=$1 BASE=$2 NEW=$3 SCENE=$4 SIZE=$5 THREADS=${6:-1}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
wall() { # BINARY: seconds of wall time for one render
  local start end
  start=$(date +%s%N)
  "$1" render "$SCENE" -o "$out/image.png" --width "$SIZE" --height "$SIZE" --spp 1 \
    --threads "$THREADS" -q >/dev/null
  end=$(date +%s%N)
  echo $(((end - start) / 1000))
}
ratios=()
for i in $(seq 1 "$PAIRS"); do
  if ((i % 2)); then
    b=$(wall "$BASE")
    n=$(wall "$NEW")
  else
    n=$(wall "$NEW")
    b=$(wall "$BASE")
  fi
  ratio=$(awk -v n="$n" -v b="$b" 'BEGIN { printf "%.4f", n / b }')
  ratios+=("$ratio")
  awk -v i="$i" -v n="$n" -v b="$b" -v r="$ratio" \
    'BEGIN { printf "pair %d: base %.3f s, new %.3f s, new/base %s\n", i, b / 1e6, n / 1e6, r }'
done
printf '%s\n' "${ratios[@]}" | sort -g | awk '{ a[NR] = $1 }
  END { m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2
        printf "median new/base over %d pairs: %.4f\n", NR, m }'
