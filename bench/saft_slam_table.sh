#!/usr/bin/env bash
# The SAFT table of issue 8 (the source's Figures 3.8 and 3.9): ATE RMSE of ORB, offline
# SAFT, continuous SAFT and discrete SAFT, median of RUNS runs each, on
#   lab-room     generated, handheld, FRAMES frames, seed 1
#   low-texture  generated, handheld, FRAMES frames, seed 1
#   blurred      generated lab-room, handheld, 20 ms motion blur, FRAMES frames, seed 2
#   blurred-33ms the same motion with a 33 ms shutter (the longest at 30 fps)
#   fading       generated lab-room, handheld, the light fading to 5 % (auto-gain: noise x20), seed 3
#   kitchen      the real ../shared/data/7scenes-kitchen (first FRAMES frames; skipped when absent)
#   NAME=DIR     any other sequence in the TUM RGB-D layout with groundtruth.txt and camera.yaml
#                (for example the source's fr1-room=/data/tum/rgbd_dataset_freiburg1_room, converted)
# with local mapping in its thread (as a user runs it), plus tracked frames, frames per
# second and, for the learning modes, frames per weight update. Online learning runs in its
# own thread, so runs differ: that is why the median. METHODS may add `checked`: continuous
# with --saft-handover-check (a held-out quarter of each batch gates the hand-over), and
# `calibrated`: continuous with --saft-calibrate-decision (the hinge decision fitted to the
# pre-trained net on the first batch).
# EXTRA adds flags to every SAFT run (for example another net: --saft-weights W --vocabulary V)
# and TAG names the output folder (bench-out/saft_slam-TAG), so such runs keep their own cache.
#   RUNS=5 FRAMES=300 bash bench/saft_slam_table.sh   -> bench-out/saft_slam/table.md, table.json
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-5}
FRAMES=${FRAMES:-300}
METHODS=${METHODS:-"orb offline continuous discrete"}
SEQUENCES=${SEQUENCES:-"lab-room low-texture blurred blurred-33ms fading kitchen"}
B=$PWD/build/release/apps/builtscene/builtscene
EXTRA=${EXTRA:-}
TAG=${TAG:-}
OUT=$PWD/bench-out/saft_slam${TAG:+-$TAG}
DATA=$PWD/bench-out/saft_slam/data
mkdir -p "$OUT"
dataset() {
  case $1 in
    lab-room) echo "$DATA/lab-room" ;;
    low-texture) echo "$DATA/low-texture" ;;
    blurred) echo "$DATA/blurred" ;;
    blurred-33ms) echo "$DATA/blurred-33ms" ;;
    fading) echo "$DATA/fading" ;;
    kitchen) echo "$PWD/../shared/data/7scenes-kitchen" ;;
    *=*) echo "${1#*=}" ;;
  esac
}
make_data() {
  local d
  d=$(dataset "$1")
  [ -f "$d/rgb.txt" ] && return 0
  case $1 in
    lab-room) "$B" synth rgbd --scene lab-room --motion handheld --frames "$FRAMES" --seed 1 --out "$d" >/dev/null ;;
    low-texture) "$B" synth rgbd --scene low-texture --motion handheld --frames "$FRAMES" --seed 1 --out "$d" >/dev/null ;;
    blurred) "$B" synth rgbd --scene lab-room --motion handheld --blur --frames "$FRAMES" --seed 2 --out "$d" >/dev/null ;;
    blurred-33ms) "$B" synth rgbd --scene lab-room --motion handheld --exposure-ms 33 --frames "$FRAMES" --seed 2 --out "$d" >/dev/null ;;
    fading) "$B" synth rgbd --scene lab-room --motion handheld --light-fade 0.05 --frames "$FRAMES" --seed 3 --out "$d" >/dev/null ;;
    kitchen) [ -d "$d" ] || return 1 ;;
    *) return 1 ;;
  esac
}
NAMES=""
for entry in $SEQUENCES; do
  seq=${entry%%=*}
  NAMES="$NAMES $seq"
  if ! make_data "$entry"; then echo "saft_slam_table: $entry: no data, skipped" >&2; continue; fi
  d=$(dataset "$entry")
  for method in $METHODS; do
    for run in $(seq 1 "$RUNS"); do
      tag="$seq-$method-$run"
      [ -f "$OUT/$tag.ate.json" ] && continue
      case $method in
        orb) args=(--descriptor orb) ;;
        checked) args=(--descriptor saft --saft-mode continuous --saft-handover-check) ;;
        calibrated) args=(--descriptor saft --saft-mode continuous --saft-calibrate-decision) ;;
        *) args=(--descriptor saft --saft-mode "$method") ;;
      esac
      # shellcheck disable=SC2206
      [ "$method" = orb ] || args+=($EXTRA)
      "$B" slam --dataset "$d" --max-frames "$FRAMES" --trajectory "$OUT/$tag.txt" "${args[@]}" \
        --inliers-out "$OUT/$tag.inliers.csv" --json > "$OUT/$tag.json" 2> "$OUT/$tag.log" || true
      "$B" eval ate --gt "$d/groundtruth.txt" --est "$OUT/$tag.txt" --json > "$OUT/$tag.ate.json" 2>> "$OUT/$tag.log" \
        || echo '{"rmse": null}' > "$OUT/$tag.ate.json"
      echo "saft_slam_table: $tag done" >&2
    done
  done
done
python3 - "$OUT" "$RUNS" "$FRAMES" "$NAMES" "$METHODS" <<'PY'
import json, os, statistics, sys
out, runs, frames = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
seqs, methods = sys.argv[4].split(), sys.argv[5].split()
names = {"orb": "ORB", "offline": "offline SAFT", "continuous": "continuous SAFT", "discrete": "discrete SAFT",
         "checked": "continuous SAFT, hand-over check", "calibrated": "continuous SAFT, calibrated decision"}
rows, table = [], {}
for s in seqs:
    for m in methods:
        ates, tracked, fps, fpu, n = [], [], [], [], None
        for r in range(1, runs + 1):
            tag = f"{s}-{m}-{r}"
            try:
                a = json.load(open(f"{out}/{tag}.ate.json")); j = json.load(open(f"{out}/{tag}.json"))
            except (OSError, ValueError):
                continue
            if a.get("rmse") is not None: ates.append(a["rmse"])
            tracked.append(j["tracked_frames"]); fps.append(j["fps"]); n = j["frames"]
            sa = j.get("features", {}).get("saft")
            if sa and sa["weight_updates"] > 0: fpu.append(sa["frames_per_update"])
        if not tracked: continue
        e = {"runs": len(tracked), "ate_rmse_median": statistics.median(ates) if ates else None,
             "ate_rmse_runs": ates, "tracked_median": statistics.median(tracked), "tracked_min": min(tracked), "frames": n,
             "fps_median": statistics.median(fps), "frames_per_update_median": statistics.median(fpu) if fpu else None}
        table.setdefault(s, {})[m] = e
        ate = "lost" if e["ate_rmse_median"] is None else "%.2f cm" % (100 * e["ate_rmse_median"])
        spread = "" if not ates else " (%.2f-%.2f)" % (100 * min(ates), 100 * max(ates))
        rows.append(f"| {s} | {names.get(m, m)} | {ate}{spread} | {e['tracked_min']}-{max(tracked)}/{n} | "
                    f"{e['fps_median']:.1f} | {'-' if e['frames_per_update_median'] is None else '%.1f' % e['frames_per_update_median']} |")
json.dump(table, open(f"{out}/table.json", "w"), indent=1)
md = ["| sequence | method | ATE RMSE, median (min-max) | tracked (min-max) | fps | frames per weight update |",
      "| --- | --- | --- | --- | --- | --- |"] + rows
open(f"{out}/table.md", "w").write("\n".join(md) + "\n")
print("\n".join(md))
PY
