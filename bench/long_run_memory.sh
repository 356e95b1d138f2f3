#!/usr/bin/env bash
# Long runs: does memory grow with the run's length? Simulates a 60 s desk scene (the built-in hand-held
# motion, 20 Hz frames, 10 ms exposure, sigma_C 0.03, 0.1 Hz/px noise; kept in OUT_DIR for later calls),
# runs `eds run` over its first 20, 40 and 60 s and prints the peak resident memory of each
# (summary.json's peak_rss_mb), its growth from the 20 s run, the keyframes and the ATE of the
# event-rate poses.
# Usage: bench/long_run_memory.sh [EDS_PROGRAM] [OUT_DIR]  (default build/release/eds, /tmp/eds_long_run;
# RUNS=3 takes the median of three runs per length; EDS_RUN_ARGS adds options to every `eds run`)
set -euo pipefail
cd "$(dirname "$0")/.."
EDS="$(realpath "${1:-build/release/eds}")"
OUT="${2:-/tmp/eds_long_run}"
RUNS="${RUNS:-1}"
[ -x "$EDS" ] || { echo "error: no program $EDS (build the release preset first: scripts/build)" >&2; exit 1; }
mkdir -p "$OUT"
seq="$OUT/sim_desk_60s"
[ -f "$seq/groundtruth.txt" ] || "$EDS" simulate --preset desk --duration 60 --fps 20 --exposure 0.01 \
  --contrast-noise 0.03 --noise-rate 0.1 --no-depth --gzip --out "$seq" > /dev/null

median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
printf "| run length | peak RSS (MB) | growth from 20 s | keyframes | ATE events (cm) |\n|---|---|---|---|---|\n"
base=""
for d in 20 40 60; do
  rss_all=""
  for r in $(seq 1 "$RUNS"); do
    run="$OUT/run_${d}s_$r"
    rm -rf "$run"
    # shellcheck disable=SC2086
    "$EDS" run "$seq" --duration "$d" --out "$run" ${EDS_RUN_ARGS:-} > "$run.log" 2>&1
    rss_all+="$(python3 -c "import json; print(json.load(open('$run/summary.json'))['peak_rss_mb'])") "
  done
  rss=$(echo "$rss_all" | tr ' ' '\n' | grep . | median)
  [ -n "$base" ] || base=$rss
  kf=$(python3 -c "import json; print(json.load(open('$run/summary.json'))['counts']['keyframes'])")
  ate=$("$EDS" eval --gt "$run/groundtruth.txt" --est "$run/trajectory_events.txt" |
    awk '$1 == "translation" && $NF == "cm" {print $2}')
  growth=$(awk -v a="$rss" -v b="$base" 'BEGIN {printf "%+.1f %%", 100 * (a / b - 1)}')
  printf "| %d s | %.1f | %s | %s | %s |\n" "$d" "$rss" "$growth" "$kf" "$ate"
done
