#!/usr/bin/env bash
# Renders every frame of an animated scene with GNU parallel: one `kardia render --frame N`
# per job, over the local cores or, with --sshloginfile, over the machines listed there
# (each needs the kardia binary and the shared output directory).
#
#   examples/farm/parallel-frames.sh SCENE OUTDIR [kardia render options…]
#
# Frames land in OUTDIR/frame_####.png; each is written atomically with its render key, so
# re-running the script (it passes --resume) renders only the frames missing or made with
# other settings. The frame count comes from kardia (--print-frame-count, which reads the
# scene's FRAMES and any --turntable among the options). When a frame fails, the frames
# already rendering finish, no new one starts, and the script exits non-zero
# (--halt soon,fail=1). Set KARDIA to the binary (default: kardia on the PATH) and
# PARALLEL_OPTS for GNU parallel's options (e.g. "-j 8 --sshloginfile nodes.txt"; over ssh
# give SCENE and OUTDIR as absolute paths on the shared directory, and KARDIA as the
# binary's path on the nodes).
set -euo pipefail
scene=$1
out=$2
shift 2
kardia=${KARDIA:-kardia}
mkdir -p "$out"
frames=$("$kardia" render "$scene" --print-frame-count "$@")
# shellcheck disable=SC2086
seq 0 $((frames - 1)) | parallel ${PARALLEL_OPTS:-} --halt soon,fail=1 \
  "$kardia" render "$scene" --frame {} --resume --quiet -o "$out/frame_####.png" "$@"
