#!/usr/bin/env bash
# Renders one large frame as N row bands with GNU parallel (`kardia render --tile I/N`), then
# joins them with `kardia assemble` into the image a single machine would have made, byte for
# byte.
#
#   examples/farm/parallel-tiles.sh SCENE N OUT.png [kardia render options…]
#
# The bands go to OUT.png.parts/ beside the output (on the shared directory, so that nodes
# reached with --sshloginfile write there too; give absolute paths then) with --resume: a
# re-run after a failure renders only the bands missing or made with other settings. The
# folder is removed once the join succeeded. Set KARDIA to the binary (default: kardia on the
# PATH) and PARALLEL_OPTS for GNU parallel.
set -euo pipefail
scene=$1
tiles=$2
output=$3
shift 3
kardia=${KARDIA:-kardia}
ext=${output##*.}
parts="$output.parts"
mkdir -p "$parts"
# shellcheck disable=SC2086
seq 0 $((tiles - 1)) | parallel ${PARALLEL_OPTS:-} --halt soon,fail=1 \
  "$kardia" render "$scene" --tile {}/"$tiles" --resume --quiet -o "$parts/part_{}.$ext" "$@"
parts_list=()
for ((i = 0; i < tiles; i++)); do parts_list+=("$parts/part_$i.$ext"); done
"$kardia" assemble "${parts_list[@]}" -o "$output"
rm -rf "$parts"
