#!/usr/bin/env bash
# End-to-end SLAM benchmark on the real 7scenes-kitchen sequence (1000 frames, 640x480, 1000
# ORB features): per-stage medians and p95 from the --json summary, and the frame rate.
# Output: bench-out/slam_kitchen.json (the full summary) and a line on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data/7scenes-kitchen
if [ ! -d "$data" ]; then
  echo "slam_kitchen: $data not found, skipped" >&2
  exit 0
fi
mkdir -p bench-out
build/release/apps/builtscene/builtscene slam --dataset "$data" \
  --trajectory bench-out/slam_kitchen_traj.txt --keyframes bench-out/slam_kitchen_kf.txt --json \
  > bench-out/slam_kitchen.json
python3 - <<'PY' >&2
import json
j = json.load(open("bench-out/slam_kitchen.json"))
s = j["stage_ms"]
print("slam_kitchen: tracked %d/%d, keyframes %d, fps %.1f (wall), tracking fps (1000/median frame) %.1f" %
      (j["tracked_frames"], j["frames"], j["keyframes"], j["fps"], j["tracking_fps_median"]))
for k in ("extraction", "tracking", "local_map", "frame", "local_ba"):
    if k in s:
        print("  %-10s median %6.2f ms  p95 %6.2f ms" % (k, s[k]["median"], s[k]["p95"]))
print("  local mapping max queue %d" % j["local_mapping"]["max_queue"])
PY
