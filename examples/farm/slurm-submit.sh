#!/usr/bin/env bash
# Submits a frame of SCENE as TILES row bands (a job array) and the join step that runs after
# the whole array (afterany), then the animation's frames as a second array.
#
#   examples/farm/slurm-submit.sh SCENE OUTDIR TILES
#
# Prints the job ids. Every node needs the kardia binary (KARDIA, default kardia) and OUTDIR.
set -euo pipefail
scene=$1
out=$2
tiles=$3
here=$(cd "$(dirname "$0")" && pwd)
# The frame count as kardia reads it (the scene's FRAMES; add --turntable N to KARDIA_ARGS).
# shellcheck disable=SC2086
frames=$("${KARDIA:-kardia}" render "$scene" --print-frame-count ${KARDIA_ARGS:-})
mkdir -p "$out"
export SCENE=$scene OUT=$out TILES=$tiles IMAGE=frame_0000_tiled.png RECIPES=$here
tiles_job=$(sbatch --parsable --chdir="$out" --array=0-$((tiles - 1)) --export=ALL "$here/slurm-tiles.sbatch")
# afterany: the join runs whatever became of the bands (never PENDING forever after a failed
# band) and fails naming the missing ones, with the command that re-runs them.
join_job=$(sbatch --parsable --chdir="$out" --dependency=afterany:"$tiles_job" --export=ALL "$here/slurm-assemble.sbatch")
frames_job=$(sbatch --parsable --chdir="$out" --array=0-$((frames - 1)) --export=ALL "$here/slurm-frames.sbatch")
echo "tiles array: $tiles_job  assemble (afterany): $join_job  frames array: $frames_job"
