#!/usr/bin/env bash
# How far each stage could gain from 2 to 16 threads given how its loops
# are cut into pieces (issue #39), on a machine with fewer cores: runs the
# benchmarks FILTER matches with VOXD_SCHEDULE_SIMULATION set
# (bench/schedule_simulation.h: every piece timed one after another, then
# scheduled on the loop's threads as parallel_for claims them) and pairs
# each 2-thread benchmark with its 16-thread twin. Prints the simulated
# times, the serial time outside loops, and the bound 2 -> 16, which unlike
# bench/serial_fraction.sh's Amdahl bound counts too few or uneven pieces.
# Neither sees memory bandwidth, or the wake-up of the kept threads a loop
# hands its pieces to (bench/loop_overhead_bench.cpp measures that).
#   bench/schedule_bound.sh BINARY FILTER
#   bench/schedule_bound.sh build/bench/analysis_stages_bench 'torus/res:512/threads:(2|16)/'
# Benchmarks are paired by a "threads:N" in their names (stages_bench's
# BM_VoxelizeRunsToRle takes its threads from VOXD_THREADS instead, and is
# left out).
set -euo pipefail
binary=$1
filter=$2
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
VOXD_SCHEDULE_SIMULATION=1 "$binary" --benchmark_filter="$filter" --benchmark_out="$out" \
  --benchmark_out_format=json > /dev/null 2>&1
python3 - "$out" << 'PY'
import json, re, statistics, sys
runs = {}
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("run_type") != "iteration" or "simulated_ms" not in b:
        continue
    m = re.search(r"threads:(\d+)", b.get("run_name") or b["name"])
    if not m:
        continue
    key = re.sub(r"/(iterations|repeats|min_time):[^/]*|/real_time", "",
                 (b.get("run_name") or b["name"]).replace(m.group(0), "threads:N"))
    runs.setdefault((key, int(m.group(1))), []).append(b)
print(f"{'section':<48} {'2 thr ms':>9} {'16 thr ms':>10} {'serial ms':>10} {'pieces':>8} {'2->16':>6}")
for key in sorted({k for k, _ in runs}):
    two, sixteen = runs.get((key, 2)), runs.get((key, 16))
    if not two or not sixteen:
        continue
    med = lambda rs, c: statistics.median(r[c] for r in rs)
    a, b = med(two, "simulated_ms"), med(sixteen, "simulated_ms")
    print(f"{key:<48} {a:9.1f} {b:10.1f} {med(sixteen, 'serial_ms'):10.1f} "
          f"{med(sixteen, 'pieces_in_loops'):8.0f} {a / b:5.1f}x")
PY
