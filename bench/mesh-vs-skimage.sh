#!/usr/bin/env bash
# `kardia mesh` against scikit-image's marching_cubes (Lewiner) at the same distance from the
# exact surface (issue 34, item 4; docs/mesh.md, "Against marching cubes"): torus, heart,
# Kummer's quartic and Barth's sextic (clipped to their balls). For each: kardia's meshing time
# (extraction + coarsening, from its summary; the time column compared) beside its whole run
# (release build, at the tolerance compared: with its accuracy measurement, check and file), with its
# triangles, peak memory and its two-sided Hausdorff estimate; then scikit-image on an n³ grid
# refined by 1.25× until its mesh is as close (both measured by `kardia mesh --measure`), with
# the time of sampling plus marching (without the interpreter's start or the file).
# See bench/mesh_vs_skimage.py. Usage:
#
#   bench/mesh-vs-skimage.sh [BINARY]
#     BINARY  the kardia binary (default: target/release/kardia, built with cargo first)
#
# ONLY=REGEX runs only the surfaces whose name matches; SCALES="1 0.5 0.25" compares at
# those shares of kardia's default tolerance (1% of the clip radius; default "1"), both
# meshes measured at the grid step of that tolerance; REPEAT=N times each side N times,
# interleaved, and compares the medians (default 3); NMAX=N caps scikit-image's grid
# (default 400: 400³ samples are 512 MB); KEEP=DIR keeps the meshes in DIR. Makes its own
# virtual environment .venv-bench-mesh (scikit-image, numpy, trimesh), never the system Python.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-}
if [ -z "$BIN" ]; then
  cargo build --release -q
  BIN=target/release/kardia
fi
if ! .venv-bench-mesh/bin/python -c "import skimage, numpy, trimesh" >/dev/null 2>&1; then
  rm -rf .venv-bench-mesh
  python3 -m venv .venv-bench-mesh
  .venv-bench-mesh/bin/pip install -q scikit-image numpy trimesh
fi
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (apt-get install time)" >&2; exit 1; }
dir=${KEEP:-$(mktemp -d)}
mkdir -p "$dir"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$dir"' EXIT
.venv-bench-mesh/bin/python bench/mesh_vs_skimage.py "$BIN" "$dir"
