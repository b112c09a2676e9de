#!/usr/bin/env bash
# Real stills table (issue 9 acceptance): every still of ../shared/data/barcodes-real rotated by
# 0, 30, 45, 60 and 90 degrees and pasted into a larger cluttered frame; decoder alone vs
# pipeline per angle. Runs the slow test on all stills and prints its table.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p bench-out
BUILTSCENE_STILLS_ALL=1 build/release/tests/barcode/barcode_slow_test --gtest_filter='RealStills.*' 2>/dev/null \
  | grep -E '^ *(angle|[0-9]+ )' | tee bench-out/barcodes_stills.txt
