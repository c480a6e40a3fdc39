#!/usr/bin/env bash
# Serial fractions by instruction count (issue #39), for a machine with too
# few cores to measure how a stage scales. Runs each benchmark FILTER matches
# under callgrind, a process each, instrumenting only the section the
# benchmark marks (bench/callgrind_section.h: its first timed loop, not its
# fixtures), and prints for each: every thread's instructions; those inside
# the pieces of work parallel_for and the ordered pipeline hand to threads
# (voxd::detail::parallel_work, the outermost on each thread); the rest,
# which is serial; its share; and Amdahl's bound on the speed-up from 2 to
# 16 threads, (s + p/2) / (s + p/16). The bound takes every piece of work as
# divisible: a loop of fewer than 16 pieces, or bound by memory bandwidth,
# gains less.
#   bench/serial_fraction.sh BINARY FILTER
#   bench/serial_fraction.sh build/bench/analysis_stages_bench 'torus/res:256/threads:16/'
set -euo pipefail
binary=$1
filter=$2
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mapfile -t benchmarks < <("$binary" --benchmark_filter="$filter" --benchmark_list_tests)
[[ ${#benchmarks[@]} -gt 0 ]] || { echo "no benchmark matches $filter" >&2; exit 1; }
for b in "${!benchmarks[@]}"; do
  valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file="$work/cg.$b.%p" \
    "$binary" --benchmark_filter="^${benchmarks[$b]}\$" > "$work/log" 2>&1 || { cat "$work/log"; exit 1; }
done
python3 - "$work" "${#benchmarks[@]}" << 'PY'
import glob, re, subprocess, sys
work, count = sys.argv[1], int(sys.argv[2])
print(f"{'section':<44} {'instructions':>14} {'parallel':>14} {'serial':>12} {'serial %':>9} {'2->16':>6}")
for b in range(count):
    path = glob.glob(f"{work}/cg.{b}.*.1")[0]  # the process's first dump: its first section
    text = open(path, errors="replace").read()
    name = re.search(r"^desc: Trigger: Client Request: (.*)$", text, re.M).group(1)
    total = int(re.search(r"^summary: (\d+)", text, re.M).group(1))
    annotated = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                               capture_output=True, text=True, check=True).stdout
    parallel = sum(int(m.group(1).replace(",", "")) for m in re.finditer(
        r"^\s*([\d,]+) \([^)]*\)\s+.*?voxd::detail::\(anonymous namespace\)::parallel_work<", annotated, re.M))
    serial = total - parallel
    s, p = serial / total, parallel / total
    print(f"{name:<44} {total:>14,} {parallel:>14,} {serial:>12,} {100 * s:>8.2f}% {(s + p / 2) / (s + p / 16):>5.1f}x")
PY
