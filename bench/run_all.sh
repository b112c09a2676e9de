#!/usr/bin/env bash
# Runs every micro-benchmark and every end-to-end benchmark script; results in bench-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p bench-out
for exe in build/release/bench/*_bench; do
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  echo "== $name" >&2
  "$exe" --benchmark_out="bench-out/$name.json" --benchmark_out_format=json
done
for script in bench/*.sh; do
  [ "$(basename "$script")" = run_all.sh ] && continue
  echo "== $script" >&2
  bash "$script"
done
