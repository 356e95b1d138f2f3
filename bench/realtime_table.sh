#!/usr/bin/env bash
# Real time, two builds side by side: runs `eds run --realtime --speed S` of REF and NEW alternately
# (RUNS runs per build and speed, the order swapped every run) on ESIM, or on SEQ, and prints per build
# and speed the event-rate poses' ATE (median, the range of the runs not lost, how many were lost:
# ATE over LOST_CM), their coverage (median, minimum, runs at 90 % or more), the events skipped and
# the latency from an event frame's last event to its pose (medians of the runs' p50 and p95).
# The coverage and the losses move between sets of runs on a shared machine: compare builds only
# within one table, and run nothing else meanwhile.
# Usage: bench/realtime_table.sh REF NEW [OUT_DIR]   REF, NEW: build folders holding `eds`, or programs
#   SPEEDS="1 2 3", RUNS=8, LOST_CM=1 by default; SEQ: a sequence with groundtruth.txt (default ESIM);
#   EDS_RUN_ARGS: more `eds run` arguments for both builds.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
program() { if [ -d "$1" ]; then echo "$1/eds"; else echo "$1"; fi; }
REF=$(program "$1") NEW=$(program "$2")
OUT="${3:-/tmp/eds_realtime_table}"
DATA="${EDS_SHARED_DATA:-../shared/data}"
SEQ="${SEQ:-$DATA/esim_poster6dof_planar}"
SPEEDS="${SPEEDS:-1 2 3}"
RUNS="${RUNS:-8}"
LOST_CM="${LOST_CM:-1}"
read -r -a extra <<< "${EDS_RUN_ARGS:-}"
for b in "$REF" "$NEW"; do [ -x "$b" ] || { echo "error: no eds program at $b" >&2; exit 1; }; done
[ -f "$SEQ/groundtruth.txt" ] || { echo "error: no groundtruth.txt in $SEQ" >&2; exit 1; }
mkdir -p "$OUT"

run_one() {  # tag program speed run
  local dir="$OUT/run_${1}_x${3}_$4"
  rm -rf "$dir"
  if "$2" run "$SEQ" --out "$dir" --realtime --speed "$3" "${extra[@]}" > "$dir.log" 2>&1; then
    "$NEW" eval --gt "$SEQ/groundtruth.txt" --est "$dir/trajectory_events.txt" --json "$dir/eval.json" \
      > /dev/null 2>&1 || echo "warning: $1 x$3 run $4: no evaluation" >&2
  else
    echo "warning: $1 x$3 run $4 failed" >&2
  fi
}

for speed in $SPEEDS; do
  for run in $(seq "$RUNS"); do
    order=(ref new)
    [ $((run % 2)) -eq 0 ] && order=(new ref)
    for tag in "${order[@]}"; do
      if [ "$tag" = ref ]; then run_one ref "$REF" "$speed" "$run"; else run_one new "$NEW" "$speed" "$run"; fi
    done
  done
  echo "x$speed: $RUNS runs of each build done" >&2
done

/usr/bin/python3 - "$OUT" "$RUNS" "$LOST_CM" $SPEEDS <<'PY'
import json, statistics, sys
out, runs, lost_cm, speeds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4:]

def load(tag, speed, r):
    d = f"{out}/run_{tag}_x{speed}_{r}"
    try:
        return json.load(open(f"{d}/summary.json")), json.load(open(f"{d}/eval.json"))
    except (OSError, ValueError):
        return None

med = statistics.median
print(f"| speed | build | runs | ATE median cm (range not lost) | lost (> {lost_cm:g} cm) | coverage median (min) "
      "| runs >= 90 % | events skipped (median) | latency p50 / p95 ms (medians) |")
print("|---|---|---|---|---|---|---|---|---|")
for speed in speeds:
    for tag in ("ref", "new"):
        got = [x for r in range(1, runs + 1) if (x := load(tag, speed, r))]
        if not got:
            print(f"| x{speed} | {tag.upper()} | 0 | - | - | - | - | - | - |")
            continue
        ate = [100 * e["trans"]["rmse"] for _, e in got]
        cov = [e["coverage"] for _, e in got]
        kept = [a for a in ate if a <= lost_cm]
        rng = f"{min(kept):.2f}-{max(kept):.2f}" if kept else "-"
        rt = [s["realtime"] for s, _ in got]
        skipped = med([r["events_skipped"] for r in rt]) / 1e6
        p50 = med([r["latency_ms"]["median"] for r in rt])
        p95 = med([r["latency_ms"]["p95"] for r in rt])
        print(f"| x{speed} | {tag.upper()} | {len(got)} | {med(ate):.3f} ({rng}) | {len(ate) - len(kept)} "
              f"| {med(cov):.3f} ({min(cov):.3f}) | {sum(c >= 0.9 for c in cov)} | {skipped:.2f} M "
              f"| {p50:.0f} / {p95:.0f} |")
PY
