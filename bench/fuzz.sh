#!/usr/bin/env bash
# The long scene-fuzzing campaign (docs/reliability.md):
#   bench/fuzz.sh [CASES] [SEED] [THREADS]     (defaults: 1000000 cases, seed 1, 1 thread)
# Builds and runs examples/fuzz.rs in the dev profile (debug assertions and overflow checks
# on) and prints the counts. Exits non-zero if any case panicked, rendered a non-finite
# pixel, got a malformed error or was slow.
set -euo pipefail
cd "$(dirname "$0")/.."
cases=${1:-1000000}
seed=${2:-1}
threads=${3:-1}
cargo build --example fuzz
exec target/debug/examples/fuzz "$cases" "$seed" "$threads"
