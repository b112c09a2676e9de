#!/usr/bin/env bash
# Issue 6's speed goals, end to end: the SLAM with the occupancy grid (>= 20 fps) and
# localization with the 2D pose on the grid (>= 30 fps), 640 x 480, on generated sequences.
# Per sequence: a map from seed 1 (`slam --ogm-out --map-out`), localization of seed 2 in it
# (`localize --ogm --poses2d`); RUNS runs each, the median of the JSON `fps` (wall clock,
# image decoding included) and of the per-stage medians.
#   bench/slam_ogm_speed.sh [WORKDIR]     (default /tmp/builtscene-slam-ogm-speed)
# Environment: RUNS (3).
# Output: bench-out/slam_ogm_speed.json and a line per command on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/release/apps/builtscene/builtscene}
WORK=${1:-/tmp/builtscene-slam-ogm-speed}
RUNS=${RUNS:-3}
mkdir -p "$WORK" bench-out
# name, synth arguments
sequences=("lab-room|--scene lab-room --motion handheld --frames 300 --noise kinect"
           "corridor-loop|--scene corridor-loop --motion robot --frames 400 --noise kinect")
for entry in "${sequences[@]}"; do
  name=${entry%%|*}
  args=${entry#*|}
  for seed in 1 2; do
    [ -f "$WORK/$name-$seed/rgb.txt" ] || "$BIN" -q synth rgbd $args --seed "$seed" --out "$WORK/$name-$seed"
  done
  for run in $(seq 1 "$RUNS"); do
    "$BIN" -q slam --dataset "$WORK/$name-1" --ogm-out "$WORK/$name-grid" --map-out "$WORK/$name.bsmap" \
      --trajectory "$WORK/$name-slam.txt" --json > "$WORK/$name-slam-$run.json"
    "$BIN" -q localize --dataset "$WORK/$name-2" --map "$WORK/$name.bsmap" --ogm "$WORK/$name-grid.yaml" \
      --poses2d "$WORK/$name-poses2d.csv" --trajectory "$WORK/$name-loc.txt" --json > "$WORK/$name-localize-$run.json"
  done
done
python3 - "$WORK" "$RUNS" <<'PY' > bench-out/slam_ogm_speed.json
import json, sys, statistics
work, runs = sys.argv[1], int(sys.argv[2])
out = {}
for name in ("lab-room", "corridor-loop"):
    for cmd, goal in (("slam", 20.0), ("localize", 30.0)):
        js = [json.load(open("%s/%s-%s-%d.json" % (work, name, cmd, r))) for r in range(1, runs + 1)]
        fps = [j["fps"] for j in js]
        stages = {k: statistics.median(j["stage_ms"][k]["median"] for j in js)
                  for k in js[0]["stage_ms"] if all(k in j["stage_ms"] and "median" in j["stage_ms"][k] for j in js)}
        r = {"fps_runs": fps, "fps_median": statistics.median(fps), "goal_fps": goal,
             "tracked": [j["tracked_frames"] for j in js], "frames": js[0]["frames"], "stage_ms_median": stages}
        out["%s/%s" % (name, cmd)] = r
        print("slam_ogm_speed: %-22s %5.1f fps median of %s (goal %.0f), tracked %s/%d" % (
            name + " " + cmd, r["fps_median"], ", ".join("%.1f" % f for f in fps), goal,
            r["tracked"], r["frames"]), file=sys.stderr)
print(json.dumps(out, indent=1))
PY
