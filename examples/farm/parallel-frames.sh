#!/usr/bin/env bash
# Renders every frame of an animated scene with GNU parallel: one `kardia render --frame N`
# per job, over the local cores or, with --sshloginfile, over the machines listed there
# (each needs the kardia binary and the shared output directory).
#
#   examples/farm/parallel-frames.sh SCENE OUTDIR [kardia render options…]
#
# Frames land in OUTDIR/frame_####.png; each is written atomically, so a frame file that
# exists is complete, and re-running the script (it passes --resume) renders only the frames
# still missing. Set KARDIA to the binary (default: kardia on the PATH) and PARALLEL_OPTS for
# GNU parallel's options (e.g. "-j 8 --sshloginfile nodes.txt").
set -euo pipefail
scene=$1
out=$2
shift 2
kardia=${KARDIA:-kardia}
mkdir -p "$out"
# The frame count: the scene's FRAMES n, as kardia reads it.
frames=$(sed -n 's/^[[:space:]]*[Ff][Rr][Aa][Mm][Ee][Ss][[:space:]]\+\([0-9]\+\).*/\1/p' "$scene" | head -n1)
frames=${frames:-1}
# shellcheck disable=SC2086
seq 0 $((frames - 1)) | parallel ${PARALLEL_OPTS:-} --halt now,fail=1 \
  "$kardia" render "$scene" --frame {} --resume --quiet -o "$out/frame_####.png" "$@"
