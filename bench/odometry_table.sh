#!/usr/bin/env bash
# Whole-run benchmark of `eds run`: accuracy (sim3 ATE, rotation RMSE with the orientations aligned,
# coverage) and real-time factor on
# the shared ESIM and ECD sequences and on simulated room/desk sequences (the first 8 s of the real
# poster_6dof motion, smoothed, sigma_C = 0.03, background noise), events + frames and frames only,
# at several frame rates, on the trajectories eds run writes (refined through the final keyframe poses).
# Prints a markdown table; the real-time factor is the median of RUNS runs.
# Usage: bench/odometry_table.sh [OUT_DIR]   (RUNS=3 by default; needs build/release and ../shared/data;
# EDS_RUN_ARGS="--set KEY=VALUE ..." adds options to every `eds run`, for before/after tables;
# EDS=path runs another build)
set -euo pipefail
cd "$(dirname "$0")/.."
EDS="${EDS:-build/release/eds}"
DATA="${EDS_SHARED_DATA:-../shared/data}"
OUT="${1:-/tmp/eds_odometry_table}"
RUNS="${RUNS:-3}"
mkdir -p "$OUT"
[ -x "$EDS" ] || { echo "error: build the release preset first (scripts/build)" >&2; exit 1; }
[ -d "$DATA" ] || { echo "error: shared data not found at $DATA" >&2; exit 1; }

traj="$DATA/trajectories/ecd_poster_6dof_groundtruth.txt"
for preset in room desk; do
  [ -d "$OUT/sim_$preset" ] || "$EDS" simulate --preset "$preset" --trajectory "$traj" --duration 8 --smooth 0.05 \
    --fps 20 --contrast-noise 0.03 --noise-rate 0.1 --out "$OUT/sim_$preset" > /dev/null
done

row() {  # name sequence mode rate
  local name=$1 seq=$2 mode=$3 rate=$4 args=() est=trajectory_events.txt
  [ "$mode" = frames ] && args+=(--frames-only) && est=trajectory_frames.txt
  local rtfs=() dir="$OUT/run_$(basename "$seq")_${mode}_${rate}"
  for _ in $(seq "$RUNS"); do
    # shellcheck disable=SC2086  # EDS_RUN_ARGS holds several words
    "$EDS" run "$seq" "${args[@]}" ${EDS_RUN_ARGS:-} --frame-rate "$rate" --out "$dir" > /dev/null 2>&1 || true
    rtfs+=("$(python3 -c "import json;print(json.load(open('$dir/summary.json'))['real_time_factor'])" 2>/dev/null || echo nan)")
  done
  local rtf
  rtf=$(printf '%s\n' "${rtfs[@]}" | sort -g | awk '{a[NR]=$1} END{print a[int((NR+1)/2)]}')
  local acc
  acc=$("$EDS" eval --gt "$seq/groundtruth.txt" --est "$dir/$est" 2>/dev/null |
        awk '/coverage/{c=$3} / cm$/{t=$2} /orientations aligned$/{r=$2} END{printf "%.3f | %.3f | %.1f %%", t, r, c}') || acc="lost | - | -"
  [ -n "$acc" ] || acc="no poses | - | -"
  printf '| %s | %s | %s | %s | %s | %.2f |\n' "$name" "$mode" "$([ "$rate" = 0 ] && echo full || echo "$rate Hz")" \
    "$acc" "" "$rtf" | sed 's/|  |/|/'
}

echo "| sequence | mode | frames | ATE (cm) | rot RMSE, orientations aligned (deg) | coverage | real-time factor |"
echo "|---|---|---|---|---|---|---|"
for rate in 0 12.5 5 2.5 1; do
  for mode in events frames; do row ESIM "$DATA/esim_poster6dof_planar" $mode $rate; done
done
for preset in room desk; do
  for rate in 0 5; do
    for mode in events frames; do row "$preset" "$OUT/sim_$preset" $mode $rate; done
  done
done
row slider_depth "$DATA/ecd_slider_depth" frames 0
row slider_hdr_close "$DATA/ecd_slider_hdr_close" frames 0
