#!/usr/bin/env bash
# Mutation testing: applies each one-line mutation of tests/mutation/mutations.txt to the source, one
# at a time, rebuilds only the test programs of the modules it names (ccache makes the rebuilds of
# unchanged files free), runs them, restores the file, and prints a markdown table: which test killed
# each mutation, or that it survived (the last killer of each, tests/mutation/killers.txt, runs first).
# Not part of CI.
# Usage: tests/mutation/run.sh [ID...]        (all mutations by default; BUILD=build/release)
#        MUTATIONS=FILE tests/mutation/run.sh  (another list)
#        tests/mutation/run.sh --record [ID...] (also writes each killer found to killers.txt)
set -euo pipefail
cd "$(dirname "$0")/../.."
export CCACHE_DIR="${CCACHE_DIR:-$HOME/.cache/ccache}"
BUILD="${BUILD:-build/release}"
[ -d "$BUILD" ] || scripts/build "$(basename "$BUILD")"
exec python3 tests/mutation/mutate.py --build "$BUILD" \
  --list "${MUTATIONS:-tests/mutation/mutations.txt}" "$@"
