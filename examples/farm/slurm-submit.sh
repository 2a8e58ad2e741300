#!/usr/bin/env bash
# Submits a frame of SCENE as TILES row bands (a job array) and the join step that depends on
# the whole array, then the animation's frames as a second array.
#
#   examples/farm/slurm-submit.sh SCENE OUTDIR TILES
#
# Prints the job ids. Every node needs the kardia binary (KARDIA, default kardia) and OUTDIR.
set -euo pipefail
scene=$1
out=$2
tiles=$3
here=$(cd "$(dirname "$0")" && pwd)
frames=$(sed -n 's/^[[:space:]]*[Ff][Rr][Aa][Mm][Ee][Ss][[:space:]]\+\([0-9]\+\).*/\1/p' "$scene" | head -n1)
frames=${frames:-1}
mkdir -p "$out"
export SCENE=$scene OUT=$out TILES=$tiles IMAGE=frame_0000_tiled.png
tiles_job=$(sbatch --parsable --chdir="$out" --array=0-$((tiles - 1)) --export=ALL "$here/slurm-tiles.sbatch")
join_job=$(sbatch --parsable --chdir="$out" --dependency=afterok:"$tiles_job" --export=ALL "$here/slurm-assemble.sbatch")
frames_job=$(sbatch --parsable --chdir="$out" --array=0-$((frames - 1)) --export=ALL "$here/slurm-frames.sbatch")
echo "tiles array: $tiles_job  assemble (afterok): $join_job  frames array: $frames_job"
