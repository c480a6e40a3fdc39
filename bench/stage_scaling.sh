#!/usr/bin/env bash
# How each stage of the analysis report scales with threads (issue #39):
# runs analysis_stages_bench builds, each given as LABEL=BINARY, on the
# benchmark torus at 512^3 with 1, 2, 4, 8 and 16 threads, one after the
# other, and writes OUT_DIR/LABEL.json (Google Benchmark's JSON) and a table
# of medians and speed-ups from 2 threads to the others. For a machine with
# 16 cores or more (the lent GPU machines); on 2 cores use the filter in
# analysis_stages_bench.cpp's header instead.
#   bench/stage_scaling.sh OUT_DIR before=old/analysis_stages_bench after=build/bench/analysis_stages_bench
set -euo pipefail
out=$1
shift
mkdir -p "$out"
filter="${FILTER:-torus/res:512/threads:(1|2|4|8|16)/}"
for pair in "$@"; do
  label=${pair%%=*}
  binary=${pair#*=}
  "$binary" --benchmark_filter="$filter" --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/$label.json" --benchmark_out_format=json > "$out/$label.txt" 2>&1
done
python3 - "$out" "$@" <<'PY'
import json, re, sys
out, pairs = sys.argv[1], sys.argv[2:]
for pair in pairs:
    label = pair.split('=', 1)[0]
    runs = json.load(open(f"{out}/{label}.json"))["benchmarks"]
    median = {}
    for r in runs:
        if r.get("aggregate_name") != "median":
            continue
        m = re.match(r"BM_(\w+)/torus/res:(\d+)/threads:(\d+)/", r["name"])
        median[(m.group(1), int(m.group(3)))] = r["real_time"]
    print(f"## {label} (median ms; speed-up over 2 threads)")
    stages = sorted({s for s, _ in median})
    for s in stages:
        cells = []
        for t in (1, 2, 4, 8, 16):
            if (s, t) in median:
                up = median.get((s, 2), 0) / median[(s, t)] if median[(s, t)] else 0
                cells.append(f"{t}: {median[(s, t)]:.0f} ({up:.1f}x)")
        print(f"{s}: " + ", ".join(cells))
PY
