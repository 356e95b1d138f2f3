#!/usr/bin/env bash
# Speed of two builds side by side: runs `eds run` of REF and NEW alternately (ROUNDS rounds, the order
# swapped every round so that drift in the machine's load falls on both) on the ESIM sequence, a
# simulated desk (hand-held poster_6dof motion, 0.8 M events/s), a simulated rotation-heavy room
# (shapes_rotation 4-12 s, 1.4 M events/s), events + frames and frames only, and on the simulated
# room at 640x480 (14 M events/s, events + frames). Prints per sequence the median real-time factor of
# each build, their ratio NEW / REF, both builds' ATE, and NEW's time by stage (summary.json).
# Usage: bench/speed_table.sh REF NEW [OUT_DIR]   REF, NEW: build folders holding `eds`, or the programs
#   e.g. bench/speed_table.sh /tmp/ref/build/release build/release
#   ROUNDS=3 by default; SEQUENCES="esim desk rotation vga" (any subset); needs ../shared/data.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
program() { if [ -d "$1" ]; then echo "$1/eds"; else echo "$1"; fi; }
REF=$(program "$1") NEW=$(program "$2")
OUT="${3:-/tmp/eds_speed_table}"
DATA="${EDS_SHARED_DATA:-../shared/data}"
ROUNDS="${ROUNDS:-3}"
SEQUENCES="${SEQUENCES:-esim desk rotation vga}"
for b in "$REF" "$NEW"; do [ -x "$b" ] || { echo "error: no eds program at $b" >&2; exit 1; }; done
[ -d "$DATA" ] || { echo "error: shared data not found at $DATA" >&2; exit 1; }
mkdir -p "$OUT"
traj="$DATA/trajectories"
noise=(--smooth 0.04 --contrast-noise 0.03 --noise-rate 0.1 --exposure 0.01 --fps 20)

simulate() {  # name args...: simulates once into $OUT/sim_<name> (kept for later tables)
  local name=$1
  shift
  [ -f "$OUT/sim_$name/groundtruth.txt" ] || "$NEW" simulate "$@" --out "$OUT/sim_$name" > /dev/null
  echo "$OUT/sim_$name"
}

declare -A seq_of
for s in $SEQUENCES; do
  case $s in
    esim) seq_of[esim]="$DATA/esim_poster6dof_planar" ;;
    desk) seq_of[desk]=$(simulate desk --preset desk --trajectory "$traj/ecd_poster_6dof_groundtruth.txt" \
                           --duration 8 "${noise[@]}") ;;
    rotation) seq_of[rotation]=$(simulate rotation --preset room --trajectory \
                           "$traj/ecd_shapes_rotation_groundtruth.txt" --t-start 4 --duration 8 "${noise[@]}") ;;
    vga) seq_of[vga]=$(simulate vga --preset room --resolution 640x480 --duration 5 --fps 20 --seed 3) ;;
    *) echo "error: unknown sequence $s (esim desk rotation vga)" >&2; exit 2 ;;
  esac
done

cases=()
for s in $SEQUENCES; do
  cases+=("$s:events")
  [ "$s" = vga ] || cases+=("$s:frames")
done

run_one() {  # build_tag program case round
  local tag=$1 bin=$2 c=$3 round=$4 seq=${seq_of[${3%%:*}]} args=()
  [ "${c##*:}" = frames ] && args+=(--frames-only)
  local dir="$OUT/run_${c/:/_}_${tag}_$round"
  "$bin" run "$seq" "${args[@]}" --out "$dir" > "$dir.log" 2>&1 || echo "warning: $tag $c round $round failed" >&2
}

for round in $(seq "$ROUNDS"); do
  order=(ref new)
  [ $((round % 2)) -eq 0 ] && order=(new ref)
  for c in "${cases[@]}"; do
    for tag in "${order[@]}"; do
      if [ "$tag" = ref ]; then run_one ref "$REF" "$c" "$round"; else run_one new "$NEW" "$c" "$round"; fi
    done
  done
  echo "round $round of $ROUNDS done" >&2
done

/usr/bin/python3 - "$OUT" "$NEW" "$ROUNDS" "${cases[@]}" <<'PY'
import json, os, statistics, subprocess, sys
out, new_bin, rounds, cases = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]

def summary(c, tag, r):
    try:
        return json.load(open(f"{out}/run_{c.replace(':', '_')}_{tag}_{r}/summary.json"))
    except (OSError, ValueError):
        return None

def ate(c, tag):
    d = f"{out}/run_{c.replace(':', '_')}_{tag}_1"
    est = "trajectory_frames.txt" if c.endswith(":frames") else "trajectory_events.txt"
    if not os.path.exists(f"{d}/groundtruth.txt"):
        return "-"
    p = subprocess.run([new_bin, "eval", "--gt", f"{d}/groundtruth.txt", "--est", f"{d}/{est}"],
                       capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.strip().endswith(" cm"):
            return line.split()[1]
    return "lost"

print("| sequence | mode | REF real-time factor | NEW real-time factor | NEW / REF | ATE REF / NEW (cm) "
      "| NEW time by stage (s, median run), accounted |")
print("|---|---|---|---|---|---|---|")
for c in cases:
    med = {}
    for tag in ("ref", "new"):
        rtfs = [s["real_time_factor"] for r in range(1, rounds + 1) if (s := summary(c, tag, r))]
        med[tag] = statistics.median(rtfs) if rtfs else float("nan")
    runs = [(s["real_time_factor"], s) for r in range(1, rounds + 1) if (s := summary(c, "new", r))]
    stages = "-"
    if runs and "stages" in runs[0][1]:
        s = sorted(runs, key=lambda x: x[0])[len(runs) // 2][1]["stages"]
        top = sorted(s["seconds"].items(), key=lambda kv: -kv[1])
        stages = ", ".join(f"{k} {v:.2f}" for k, v in top if v >= 0.05) + f"; {100 * s['accounted_fraction']:.1f} %"
    name, mode = c.split(":")
    print(f"| {name} | {mode} | {med['ref']:.3f} | {med['new']:.3f} | {med['new'] / med['ref']:.3f} "
          f"| {ate(c, 'ref')} / {ate(c, 'new')} | {stages} |")
PY
