#!/usr/bin/env bash
# A SAFT net pre-trained on a domain foreign to the generated test worlds, as in the source
# (its net was pre-trained on Notre Dame / Liberty patches, then fine-tuned online in other
# scenes): the shipped real photographs of ../shared/data/barcodes-real and apriltag-real
# (275 training images; HPatches stays held out), plus the SAFT vocabulary of that net from
# the same generated worlds as the shipped vocabularies (scripts/make_vocabulary).
# Writes OUT_DIR/foreign.saft and OUT_DIR/foreign.bsvoc (deterministic for a build; ~2 min).
# Used for the foreign-net table in docs/saft.md:
#   EXTRA="--saft-weights OUT_DIR/foreign.saft --vocabulary OUT_DIR/foreign.bsvoc" TAG=foreign bash bench/saft_slam_table.sh
# Usage: bash scripts/saft_train_foreign.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
B="${1:-$here/build/release}/apps/builtscene/builtscene"
out="${2:-$here/build/saft-foreign}"
data="$here/../shared/data"
for d in barcodes-real apriltag-real; do
  [[ -d "$data/$d" ]] || { echo "saft_train_foreign: $data/$d: not found (the real photographs are needed)" >&2; exit 1; }
done
mkdir -p "$out"
"$B" saft train --images "$data"/barcodes-real/*/ "$data/apriltag-real/" --every 1 \
  --keypoints 300 --warps 4 --steps 1500 --batch 128 --loss hinge --seed 1 --out "$out/foreign.saft" --json > "$out/train.json"
datasets=()
for scene in corridor-loop demo lab-room low-texture office; do  # the order the table's vocabulary was made in
  for seed in 101 202; do
    d="$out/vocab-worlds/$scene-$seed"
    [[ -f "$d/rgb.txt" ]] || "$B" synth rgbd --scene "$scene" --motion handheld --frames 40 --seed "$seed" --out "$d" >/dev/null
    datasets+=(--dataset "$d")
  done
done
"$B" vocab train "${datasets[@]}" --descriptor saft --saft-weights "$out/foreign.saft" --k 10 --levels 4 --seed 1 \
  --out "$out/foreign.bsvoc" --json > "$out/vocab.json"
echo "saft_train_foreign: $out/foreign.saft $out/foreign.bsvoc"
