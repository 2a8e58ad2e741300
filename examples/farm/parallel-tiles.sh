#!/usr/bin/env bash
# Renders one large frame as N row bands with GNU parallel (`kardia render --tile I/N`), then
# joins them with `kardia assemble` into the image a single machine would have made, byte for
# byte.
#
#   examples/farm/parallel-tiles.sh SCENE N OUT.png [kardia render options…]
#
# Set KARDIA to the binary (default: kardia on the PATH) and PARALLEL_OPTS for GNU parallel.
set -euo pipefail
scene=$1
tiles=$2
output=$3
shift 3
kardia=${KARDIA:-kardia}
ext=${output##*.}
parts=$(mktemp -d "${output%/*}/.parts.XXXXXX" 2>/dev/null || mktemp -d)
trap 'rm -rf "$parts"' EXIT
# shellcheck disable=SC2086
seq 0 $((tiles - 1)) | parallel ${PARALLEL_OPTS:-} --halt now,fail=1 \
  "$kardia" render "$scene" --tile {}/"$tiles" --quiet -o "$parts/part_{}.$ext" "$@"
"$kardia" assemble "$parts"/part_*."$ext" -o "$output"
