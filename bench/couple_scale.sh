#!/usr/bin/env bash
# The coupling scale benchmark (issue 11): a generated district of N buildings, each
# building three sub-models in its own processes (the example's wind, structure and
# controller plugins on channels WIND_i, STRUCTURE_i, CONTROL_i; the structure plugin takes
# the control force as an input, so the controller is part of every building), plus one
# district aggregator reading every STRUCTURE_i (bench/couple_scale/district.cpp): 3N+1
# model processes. Each N runs on three platforms:
#   lcm       every channel over LCM udpm (one multicast group for all)
#   mediator  every channel through the launcher's nats-server
#   hybrid    a building's channels over its own LCM group (local), the STRUCTURE_i copy
#             for the district through the mediator (bridged)
# and reports time steps per second (launch --json steps_per_second), the nats-server's
# CPU seconds (mediator_cpu_seconds) and the CPU seconds of every process of the run.
# Runs in a private network namespace (root) with a loopback multicast route.
#   BUILDINGS="2 5 10" STEPS=2000 RUNS=1 bash bench/couple_scale.sh  -> bench-out/couple_scale.json
# MODELS_PER_PROCESS=3 hosts three consecutive models per process (one building; the
# scenarios' models_per_process), a wrapper thread each: N + 1 processes instead of 3N + 1.
# PLATFORMS="lcm mediator hybrid" chooses the platforms.
# (RUN_TIMEOUT=600: a launch still running after that many seconds is stopped and left out.)
# Each launch's stderr (stall reports, where the models were when stopped) is kept in
# bench-out/couple_scale/N<buildings>/<platform>.stderr. 100 buildings, as in docs/coupling.md:
#   MODELS_PER_PROCESS=3 PLATFORMS=hybrid BUILDINGS=100 STEPS=200 RUNS=1 RUN_TIMEOUT=600 bash bench/couple_scale.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BUILDINGS=${BUILDINGS:-"2 5 10"}
STEPS=${STEPS:-1000}
RUNS=${RUNS:-1}
BIN=$PWD/build/release/apps/builtscene/builtscene
EXAMPLE=$PWD/examples/coupling/wind-structure-control
OUT=$PWD/bench-out/couple_scale
mkdir -p "$OUT"
export MODELS_PER_PROCESS=${MODELS_PER_PROCESS:-1} PLATFORMS=${PLATFORMS:-"lcm mediator hybrid"}
unshare -n bash -s "$BUILDINGS" "$STEPS" "$RUNS" "$BIN" "$EXAMPLE" "$OUT" <<'INNER'
set -euo pipefail
BUILDINGS=$1 STEPS=$2 RUNS=$3 BIN=$4 EXAMPLE=$5 OUT=$6
ip link set lo up
ip route add 224.0.0.0/4 dev lo
python3 - "$BUILDINGS" "$STEPS" "$RUNS" "$BIN" "$EXAMPLE" "$OUT" <<'PY'
import json, math, os, resource, signal, statistics, subprocess, sys, time
buildings, steps, runs = [int(b) for b in sys.argv[1].split()], int(sys.argv[2]), int(sys.argv[3])
limit = int(os.environ.get("RUN_TIMEOUT", "600"))  # seconds per launch
bin_, example, out = sys.argv[4], sys.argv[5], sys.argv[6]
end_time = steps * 0.01
per_process = int(os.environ.get("MODELS_PER_PROCESS", "1"))
platforms = os.environ.get("PLATFORMS", "lcm mediator hybrid").split()

def scenario_dir(n):
    d = os.path.join(out, f"N{n}")
    os.makedirs(d, exist_ok=True)
    head = f"dt: 0.01\nend_time: {end_time:g}\nmessages: {example}/messages.lcm\n"
    for i in range(n):
        open(f"{d}/wind_{i}.yaml", "w").write(
            f"name: wind_{i}\n{head}plugin: wind\nparameters: {{mean_speed: {25 + i % 10}, height: 100.0, roughness: 0.3, "
            f"air_density: 1.25, drag_coefficient: 1.3, area: 1200.0, frequencies: 512, max_frequency: 5.0, "
            f"ramp_time: 5.0, seed: {7 + i}}}\npublish:\n  - {{channel: WIND_{i}, type: wsc.wind_t}}\n")
        open(f"{d}/structure_{i}.yaml", "w").write(
            f"name: structure_{i}\n{head}plugin: structure\nparameters: {{mass: 3.0e5, frequency: 0.5, damping_ratio: 0.02}}\n"
            f"subscribe:\n  - {{channel: WIND_{i}, type: wsc.wind_t}}\n  - {{channel: CONTROL_{i}, type: wsc.control_t}}\n"
            f"  - {{channel: STRUCTURE_{i}, type: wsc.response_t, lag: 1, initial: {{D: 0.0, V: 0.0, A: 0.0}}}}\n"
            f"publish:\n  - {{channel: STRUCTURE_{i}, type: wsc.response_t}}\n")
        open(f"{d}/controller_{i}.yaml", "w").write(
            f"name: controller_{i}\n{head}plugin: controller\nparameters: {{enabled: true, acceleration_limit: 1.5, "
            f"mass: 3.0e5, frequency: 0.5, damping_ratio: 0.02}}\n"
            f"subscribe:\n  - {{channel: STRUCTURE_{i}, type: wsc.response_t, lag: 1, initial: {{D: 0.0, V: 0.0, A: 0.0}}}}\n"
            f"  - {{channel: WIND_{i}, type: wsc.wind_t}}\npublish:\n  - {{channel: CONTROL_{i}, type: wsc.control_t}}\n")
    subs = "".join(f"  - {{channel: STRUCTURE_{i}, type: wsc.response_t}}\n" for i in range(n))
    open(f"{d}/district.yaml", "w").write(
        f"name: district\n{head}plugin: district\nsubscribe:\n{subs}publish:\n  - {{channel: DISTRICT, type: wsc.response_t}}\n")
    plain = "".join(f"  - wind_{i}.yaml\n  - structure_{i}.yaml\n  - controller_{i}.yaml\n" for i in range(n)) + "  - district.yaml\n"
    grouped = "".join(f"  - {{config: wind_{i}.yaml, group: b{i}}}\n  - {{config: structure_{i}.yaml, group: b{i}}}\n"
                      f"  - {{config: controller_{i}.yaml, group: b{i}}}\n" for i in range(n)) + "  - district.yaml\n"
    local = ", ".join(f"WIND_{i}, STRUCTURE_{i}, CONTROL_{i}" for i in range(n))
    common = f"timeout: 60\nmodels_per_process: {per_process}\n"
    open(f"{d}/scenario-lcm.yaml", "w").write(f"name: district-{n}-lcm\ntransport: udpm://239.255.76.67:7667?ttl=0\n{common}models:\n{plain}")
    open(f"{d}/scenario-mediator.yaml", "w").write(f"name: district-{n}-mediator\ntransport: mediator\n{common}models:\n{plain}")
    open(f"{d}/scenario-hybrid.yaml", "w").write(
        f"name: district-{n}-hybrid\ntransport: mediator\n{common}local:\n  transport: udpm://239.255.76.67:7700?ttl=0\n"
        f"  channels: [{local}]\nmodels:\n{grouped}")
    return d

def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime

rows = []
for n in buildings:
    d = scenario_dir(n)
    for platform in platforms:
        sps, med, cpu = [], [], []
        for _ in range(runs):
            before = cpu_children()
            env = dict(os.environ, TMPDIR=d)
            p = subprocess.Popen([bin_, "couple", "launch", f"{d}/scenario-{platform}.yaml", "--json"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                 start_new_session=True)
            try:
                stdout, stderr = p.communicate(timeout=limit)
            except subprocess.TimeoutExpired:
                # Ctrl-C: the launcher stops its models and nats-server (a kill would orphan them).
                p.send_signal(signal.SIGINT)
                try:
                    _, stderr = p.communicate(timeout=30)
                except subprocess.TimeoutExpired:
                    p.kill()
                    _, stderr = p.communicate()
                # Whatever is left of the run (model processes die with the launcher; this is
                # the backstop) goes with its process group, so the next run starts on an idle machine.
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                open(f"{d}/{platform}.stderr", "w").write(stderr or "")
                print(f"N={n} {platform}: not finished in {limit} s (stopped)", file=sys.stderr)
                continue
            p.stdout, p.stderr = stdout, stderr
            open(f"{d}/{platform}.stderr", "w").write(stderr)  # the launcher's log (stall reports)
            if p.returncode != 0:
                print(f"N={n} {platform}: failed: {p.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
                continue
            j = json.loads(p.stdout)
            sps.append(j["steps_per_second"])
            med.append(j.get("mediator_cpu_seconds"))
            cpu.append(cpu_children() - before)
        row = {"buildings": n, "models": 3 * n + 1, "processes": math.ceil((3 * n + 1) / per_process), "platform": platform, "steps": steps, "runs": len(sps),
               "steps_per_second": statistics.median(sps) if sps else None,
               "mediator_cpu_seconds": statistics.median(med) if med and med[0] is not None else None,
               "all_processes_cpu_seconds": statistics.median(cpu) if cpu else None,
               "load_average": os.getloadavg()[0]}
        rows.append(row)
        print(json.dumps(row), flush=True)
json.dump(rows, open(os.path.join(out, "..", "couple_scale.json"), "w"), indent=2)
print("| buildings | models | model processes | platform | steps/s | nats-server CPU [s] | CPU of all processes [s] | load avg |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for r in rows:
    f = lambda v, fmt: "-" if v is None else format(v, fmt)
    print(f"| {r['buildings']} | {r['models']} | {r['processes']} | {r['platform']} | {f(r['steps_per_second'], '.0f' if (r['steps_per_second'] or 0) >= 100 else '.3g')} | "
          f"{f(r['mediator_cpu_seconds'], '.2f')} | {f(r['all_processes_cpu_seconds'], '.1f')} | {r['load_average']:.1f} |")
PY
INNER
