#!/usr/bin/env bash
# `kardia mesh` over a corpus of published implicit surfaces (docs/mesh.md, "The public
# corpora"): every surface of degree at most 16 in a surfaces.json (a list under "surfaces",
# each with "id", "degree", the equation as typed for kardia under "kardia" and its clip ball's
# "radius") meshed at the default tolerance (1% of the clip radius). Prints each failure (exit
# status other than 0, or past the time limit) and a table: how many meshed, how many the
# check refused, and the two-sided Hausdorff estimate over the tolerance in buckets (and again
# away from the parts thinner than the grid step, which the summary counts apart). Usage:
#
#   bench/mesh-corpus.sh SURFACES_JSON [BINARY]
#     SURFACES_JSON  the corpus (not in this repository)
#     BINARY         the kardia binary (default: target/release/kardia, built with cargo first)
#
# KIND="--outside" or KIND="--shell F" (the wall F × the clip radius thick) meshes that kind of
# solid instead of the inside; LIMIT=S stops each run after S seconds (default 60; such runs
# are counted apart); ONLY=REGEX runs only the ids that match; LOG=FILE writes each run's id,
# status, seconds and summary.
set -euo pipefail
cd "$(dirname "$0")/.."
CORPUS=${1:?usage: bench/mesh-corpus.sh SURFACES_JSON [BINARY]}
BIN=${2:-}
if [ -z "$BIN" ]; then
  cargo build --release -q
  BIN=target/release/kardia
fi
exec python3 bench/mesh_corpus.py "$CORPUS" "$BIN"
