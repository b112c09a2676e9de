#!/usr/bin/env bash
# Reproduces the shipped SAFT weights data/saft/saft_v1.saft from generated worlds only
# (the real HPatches sequences are held out for `builtscene saft eval`).
# Usage: bash scripts/saft_train.sh [BUILD_DIR] [WORK_DIR]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
B="${1:-$here/build/release}/apps/builtscene/builtscene"
work="${2:-$here/build/saft-train}"
mkdir -p "$work"
for scene in office corridor-loop lab-room; do
  [[ -f "$work/$scene/rgb.txt" ]] || "$B" synth rgbd --scene "$scene" --motion handheld --frames 60 --seed 7 --out "$work/$scene" >/dev/null
done
"$B" saft train --images "$work/office" "$work/corridor-loop" "$work/lab-room" --every 3 \
  --keypoints 300 --warps 4 --steps 1500 --batch 128 --loss hinge --seed 1 \
  --out "$here/data/saft/saft_v1.saft" --json
