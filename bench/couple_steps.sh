#!/usr/bin/env bash
# The coupling benchmark (issue 10): time steps per second of the wind-structure-control
# example over udpm, every model its own process, median of RUNS runs; and in the same
# network namespace, a raw LCM ping-pong (bench/couple_pingpong_bench.cpp) for the cost
# per message without the wrapper. Runs in a private network namespace (root) with a
# loopback multicast route so nothing leaves the machine and no other run interferes.
#   bash bench/couple_steps.sh            -> bench-out/couple_steps.json
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-5}
BIN=build/release/apps/builtscene/builtscene
PING=build/release/bench/couple_pingpong_bench
SCENARIO=examples/coupling/wind-structure-control/scenario.yaml
mkdir -p bench-out
OUT=bench-out/couple_steps.json
unshare -n bash -s "$RUNS" "$BIN" "$PING" "$SCENARIO" "$OUT" <<'INNER'
set -euo pipefail
RUNS=$1 BIN=$2 PING=$3 SCENARIO=$4 OUT=$5
ip link set lo up
ip route add 224.0.0.0/4 dev lo
rm -f bench-out/couple_steps_runs.jsonl
for i in $(seq "$RUNS"); do
  "$BIN" couple launch "$SCENARIO" --json 2>/dev/null >> bench-out/couple_steps_runs.jsonl
  echo >> bench-out/couple_steps_runs.jsonl
done
"$PING" --benchmark_filter=PingPong --benchmark_repetitions="$RUNS" --benchmark_format=json \
  > bench-out/couple_pingpong.json 2>/dev/null
python3 - "$OUT" <<'PY'
import json, statistics, sys
runs = [json.loads(l) for l in open("bench-out/couple_steps_runs.jsonl") if l.strip()]
sps = sorted(r["steps_per_second"] for r in runs)
ping = json.load(open("bench-out/couple_pingpong.json"))
rtt = [b["real_time"] for b in ping["benchmarks"] if b.get("run_type") == "iteration"]
unit = {"ns": 1e-3, "us": 1.0, "ms": 1e3}[ping["benchmarks"][0]["time_unit"]]
rtt_us = statistics.median(rtt) * unit
step_us = 1e6 / statistics.median(sps)
# The structure-controller cycle puts two message hops on the critical path of every step.
summary = {
    "scenario": runs[0]["scenario"], "transport": runs[0]["transport"], "runs": len(runs),
    "steps": runs[0]["steps"], "steps_per_second_median": statistics.median(sps), "steps_per_second_all": sps,
    "microseconds_per_step": step_us,
    "raw_lcm_round_trip_us_median": rtt_us, "raw_lcm_one_way_us": rtt_us / 2,
    "wrapper_us_per_critical_hop": step_us / 2, "ratio_to_raw_hop": (step_us / 2) / (rtt_us / 2),
}
json.dump(summary, open(sys.argv[1], "w"), indent=2)
print(json.dumps(summary, indent=2))
PY
INNER
