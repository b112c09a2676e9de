#!/usr/bin/env bash
# Tracking where offline SAFT loses track (issue 8): the real 7scenes-kitchen at 1/STRIDE of
# its frame rate (every STRIDE-th frame: 1.5 s between frames at 20, so big viewpoint jumps),
# RUNS runs of slam per method, tracked frames and ATE RMSE (over the tracked frames) per run.
# EXTRA adds flags to every SAFT run (another net: --saft-weights W --vocabulary V).
#   STRIDE=20 RUNS=5 METHODS="orb offline continuous discrete" bash bench/saft_sparse_kitchen.sh
set -euo pipefail
cd "$(dirname "$0")/.."
STRIDE=${STRIDE:-20}
RUNS=${RUNS:-5}
METHODS=${METHODS:-"orb offline continuous discrete"}
EXTRA=${EXTRA:-}
TAG=${TAG:-}
B=$PWD/build/release/apps/builtscene/builtscene
K=$PWD/../shared/data/7scenes-kitchen
[ -f "$K/rgb.txt" ] || { echo "saft_sparse_kitchen: $K: not found" >&2; exit 1; }
OUT=$PWD/bench-out/saft_sparse_kitchen${TAG:+-$TAG}
D=$OUT/kitchen-x$STRIDE
mkdir -p "$D"
ln -sfn "$K/rgb" "$D/rgb"
ln -sfn "$K/depth" "$D/depth"
cp "$K/camera.yaml" "$K/groundtruth.txt" "$D/"
for f in rgb depth; do
  { grep '^#' "$K/$f.txt" || true; grep -v '^#' "$K/$f.txt" | awk -v n="$STRIDE" 'NR % n == 1'; } > "$D/$f.txt"
done
for method in $METHODS; do
  line="$method:"
  for run in $(seq 1 "$RUNS"); do
    tag="x$STRIDE-$method-$run"
    case $method in
      orb) args=(--descriptor orb) ;;
      *) args=(--descriptor saft --saft-mode "$method") ;;
    esac
    # shellcheck disable=SC2206
    [ "$method" = orb ] || args+=($EXTRA)
    "$B" slam --dataset "$D" --trajectory "$OUT/$tag.txt" "${args[@]}" --json > "$OUT/$tag.json" 2> "$OUT/$tag.log" || true
    counts=$(python3 -c "import json,sys; j = json.load(open(sys.argv[1])); print('%d/%d' % (j['tracked_frames'], j['frames']))" \
             "$OUT/$tag.json" 2>/dev/null || echo "?/?")
    ate=$("$B" eval ate --gt "$D/groundtruth.txt" --est "$OUT/$tag.txt" --json 2>/dev/null \
          | python3 -c "import json,sys; print('%.2f cm' % (100 * json.load(sys.stdin)['rmse']))" 2>/dev/null || echo "-")
    line="$line $counts ($ate);"
  done
  echo "$line"
done
