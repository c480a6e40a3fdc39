#!/usr/bin/env bash
# The GPU checks of the CUDA backend (issue #40), for a machine with an
# NVIDIA GPU that has CUDA and Python but none of Debian's packages: build
# and pack here, run there, all within 5 minutes.
#   bench/gpu/check.sh pack BUILD_DIR OUT_DIR
#       packs the gpu tests, the host-side tests and the benchmark with the
#       shared libraries they need that a bare machine lacks into
#       OUT_DIR/pack.tar.xz (BUILD_DIR built with -DVOXD_CUDA=ON)
#   bench/gpu/check.sh run PACK_DIR [RESULTS_DIR]
#       unpacks PACK_DIR/pack.tar.xz and runs: the gpu tests (the kernels'
#       bytes against the CPU's: every slice function, three meshes, odd
#       grids, slab by slab; every coverage sampling, four meshes, whole,
#       in slabs and streamed; every distance band option, three meshes),
#       the host-side tests, then the benchmarks of every slice function at
#       512^3, of exact coverage at 512^3 and 1024^3 and of the band SDF at
#       512^3 on the CPU's threads (all of them, VOXD_THREADS to pin) and on
#       the GPU, and prints the speed-ups.
#       Results (gtest and benchmark JSON) go to RESULTS_DIR (default $OUT
#       when set, else ./gpu-results). Then `scaling`, below: the lent GPU
#       machines have 16 CPU cores.
#   bench/gpu/check.sh scaling PACK_DIR [RESULTS_DIR]
#       issue #39 on the machine's cores, GPU or not (about a minute): each
#       stage of the analysis report on the torus at 512^3 on 2 and 16
#       threads, the solid straight to its RLE at 2048^3 and 8192^3 on 2 and 16
#       threads, its chunks encoded by the writer and where they are made,
#       a stored 4096^3 RLE read back as runs, the streamed report,
#       radiograph and preview over a stored 2048^3 RLE's runs, a 4096 x
#       4096 16-bit PNG written in bands, the memory's own speed (read,
#       write, copy, fresh pages faulted in) and what a loop costs beyond
#       its pieces (waking the kept threads); prints the CPU's
#       layout (lscpu: cores, threads a core, memory nodes), medians and
#       speed-ups from 2 to 16 threads.
set -euo pipefail

# Unpacks PACK_DIR's pack into `root` with its libraries on the path, and
# sets `results` (RESULTS_DIR, default $OUT when set, else ./gpu-results).
unpack() {
  results=${2:-${OUT:-./gpu-results}}
  mkdir -p "$results"
  root=$(mktemp -d)
  tar -C "$root" -xJf "$1/pack.tar.xz"
  export LD_LIBRARY_PATH="$root/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
}

scaling() {
  local root=$1 results=$2 status=0
  # What "16 cores" means here: 16 cores, or 8 with two threads each, on
  # one memory node or two, decides which speed-ups are possible at all.
  lscpu > "$results/lscpu.txt" 2>&1 || nproc > "$results/lscpu.txt"
  grep -E '^(Model name|CPU\(s\)|Thread\(s\) per core|Core\(s\) per socket|Socket\(s\)|NUMA node\(s\)|L3 cache|CPU max MHz):' \
    "$results/lscpu.txt" || true
  # The memory's own speed-up from 2 to 16 threads: the ceiling of a stage
  # that streams its voxels.
  timeout 60 "$root/bin/memory_bandwidth_bench" --benchmark_filter='threads:(2|16)/' \
    --benchmark_out="$results/memory.json" --benchmark_out_format=json > /dev/null || status=1
  # What a loop costs beyond its pieces: waking the kept threads.
  timeout 30 "$root/bin/loop_overhead_bench" --benchmark_filter='threads:(1|2|16)/' --benchmark_min_time=0.2 \
    --benchmark_out="$results/loops.json" --benchmark_out_format=json > /dev/null || status=1
  timeout 240 "$root/bin/analysis_stages_bench" --benchmark_filter='torus/res:512/threads:(2|16)/' \
    --benchmark_report_aggregates_only=true --benchmark_out="$results/analysis_stages.json" \
    --benchmark_out_format=json > /dev/null || status=1
  for t in 2 16; do
    VOXD_THREADS=$t timeout 90 "$root/bin/stages_bench" --benchmark_filter='BM_VoxelizeRunsToRle/(2048|8192)/' \
      --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
      --benchmark_out="$results/runs_to_rle_$t.json" --benchmark_out_format=json > /dev/null || status=1
  done
  timeout 60 "$root/bin/stages_bench" --benchmark_filter='BM_ReadRunSlabs/res:4096/threads:(2|16)/' \
    --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$results/read_runs.json" --benchmark_out_format=json > /dev/null || status=1
  timeout 120 "$root/bin/stages_bench" --benchmark_filter='BM_Streamed(Report|Radiograph|Preview)/res:2048/threads:(2|16)/' \
    --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
    --benchmark_out="$results/streamed.json" --benchmark_out_format=json > /dev/null || status=1
  timeout 60 "$root/bin/volume_format_bench" --benchmark_filter='BM_PngGrey16/side:4096/threads:(2|16)/' \
    --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$results/png.json" --benchmark_out_format=json > /dev/null || status=1
  python3 - "$results" <<'PY' | tee "$results/scaling.txt"
import json, os, re, sys
results = sys.argv[1]
def medians(path, key):
    if not os.path.exists(path): return {}
    out = {}
    for b in json.load(open(path))["benchmarks"]:
        if b.get("aggregate_name") == "median": out[key(b["name"])] = b["real_time"]
    return out
stages = medians(f"{results}/analysis_stages.json",
                 lambda n: tuple(re.match(r"BM_(\w+)/torus/res:\d+/threads:(\d+)/", n).groups()))
print(f"{'stage (torus 512^3)':34} {'2 threads ms':>13} {'16 threads ms':>14} {'speed-up':>9}")
for stage in sorted({s for s, _ in stages}):
    a, b = stages.get((stage, "2")), stages.get((stage, "16"))
    if a and b: print(f"{stage:34} {a:13.0f} {b:14.0f} {a / b:8.1f}x")
runs = {t: medians(f"{results}/runs_to_rle_{t}.json", lambda n: "/".join(n.split("/")[1:3])) for t in ("2", "16")}
for arg, how in (("2048/0", "2048^3, RLE encoded by the writer"), ("2048/1", "2048^3, RLE encoded where made"),
                 ("8192/1", "8192^3, RLE encoded where made")):
    a, b = runs["2"].get(arg), runs["16"].get(arg)
    if a and b: print(f"{'solid ' + how:34} {a:13.0f} {b:14.0f} {a / b:8.1f}x")
reads = medians(f"{results}/read_runs.json", lambda n: re.search(r"threads:(\d+)", n).group(1))
if reads.get("2") and reads.get("16"):
    print(f"{'stored RLE 4096^3 read as runs':34} {reads['2']:13.0f} {reads['16']:14.0f} {reads['2'] / reads['16']:8.1f}x")
streamed = medians(f"{results}/streamed.json",
                   lambda n: tuple(re.match(r"BM_Streamed(\w+)/res:\d+/threads:(\d+)/", n).groups()))
for what in ("Report", "Radiograph", "Preview"):
    a, b = streamed.get((what, "2")), streamed.get((what, "16"))
    if a and b: print(f"{'streamed ' + what.lower() + ', 2048^3 runs':34} {a:13.0f} {b:14.0f} {a / b:8.1f}x")
if os.path.exists(f"{results}/memory.json"):
    rates = {}
    for b in json.load(open(f"{results}/memory.json"))["benchmarks"]:
        what, t = re.match(r"BM_Memory(\w+)/threads:(\d+)/", b["name"]).groups()
        rates[(what, t)] = b["bytes_per_second"] / 1e9
    for what in ("Read", "Write", "Copy", "FaultIn"):
        a, b = rates.get((what, "2")), rates.get((what, "16"))
        if a and b: print(f"{'memory ' + what.lower() + ', GB/s (not ms)':34} {a:13.1f} {b:14.1f} {b / a:8.1f}x")
if os.path.exists(f"{results}/loops.json"):
    times = {}
    for b in json.load(open(f"{results}/loops.json"))["benchmarks"]:
        what, t = re.match(r"BM_(\w+)/threads:(\d+)/", b["name"]).groups()
        times[(what, t)] = b["real_time"] / 1e3
    # Each thread's share of the pieces is the same on 2 and 16 threads: on
    # as many cores, the ideal is the 1-thread time (the pieces alone).
    for what, label in (("LoopOfEmptyPieces", "empty pieces"), ("LoopOfShortPieces", "16 short pieces a thread"),
                        ("OrderedPipeline", "ordered pipeline")):
        one, a, b = times.get((what, "1")), times.get((what, "2")), times.get((what, "16"))
        if a and b: print(f"{'loop, us: ' + label:34} {a:13.1f} {b:14.1f}  (1 thread: {one or 0:.1f} us)")
pngs = medians(f"{results}/png.json", lambda n: re.search(r"threads:(\d+)", n).group(1))
if pngs.get("2") and pngs.get("16"):
    print(f"{'PNG16 4096 x 4096 in bands':34} {pngs['2']:13.0f} {pngs['16']:14.0f} {pngs['2'] / pngs['16']:8.1f}x")
PY
  return $status
}


case "${1:-}" in
  pack)
    build=$2 out=$3
    stage=$(mktemp -d); trap 'rm -rf "$stage"' EXIT
    mkdir -p "$stage/bin" "$stage/lib" "$out"
    for exe in tests/slice_cuda_test tests/slice_device_test bench/slice_device_bench bench/analysis_stages_bench \
      bench/stages_bench bench/volume_format_bench bench/memory_bandwidth_bench bench/loop_overhead_bench \
      tests/coverage_cuda_test tests/coverage_device_test bench/coverage_device_bench \
      tests/sdf_cuda_test tests/sdf_device_test bench/sdf_device_bench; do
      cp "$build/$exe" "$stage/bin/"
      # The C and C++ runtimes stay behind: the GPU machine has its own, newer.
      # (grep finds nothing to keep for an executable of system libraries only.)
      ldd "$build/$exe" | awk '/=> \// {print $3}' |
        { grep -v -E '/(libc|libm|libstdc\+\+|libgcc_s|libpthread|libdl|librt|ld-linux[^/]*)\.so' || true; } |
        while read -r lib; do cp -Ln "$lib" "$stage/lib/" 2>/dev/null || true; done
    done
    tar -C "$stage" -cJf "$out/pack.tar.xz" .
    echo "$out/pack.tar.xz: $(du -h "$out/pack.tar.xz" | cut -f1)"
    ;;
  run)
    unpack "$2" "${3:-}"
    if ! nvidia-smi -L >/dev/null 2>&1; then
      echo "check.sh run: no GPU here (nvidia-smi finds none); run it on a machine with an NVIDIA GPU" >&2
      exit 1
    fi
    nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader | tee "$results/gpu.txt"
    echo "CPU threads: $(nproc)" | tee -a "$results/gpu.txt"
    status=0
    timeout 120 "$root/bin/slice_cuda_test" --gtest_output="json:$results/slice_cuda_test.json" || status=1
    timeout 60 "$root/bin/slice_device_test" --gtest_filter='-SliceWithoutGpu.*' \
      --gtest_output="json:$results/slice_device_test.json" || status=1
    timeout 150 "$root/bin/slice_device_bench" --benchmark_filter='BM_SliceDevice/[0-9]+/512/' \
      --benchmark_min_time=0.3 --benchmark_out="$results/slice_device_bench.json" --benchmark_out_format=json ||
      status=1
    python3 - "$results/slice_device_bench.json" <<'PY' | tee "$results/speedups.txt"
import json, sys
runs = {}
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("error_occurred"):
        print("error:", b["name"], b.get("error_message")); continue
    function, device = b["label"].split()
    runs.setdefault(function, {})[device] = b
print(f"{'function':22} {'cpu ms':>9} {'gpu ms':>9} {'kernel ms':>10} {'copy ms':>9} {'whole':>7} {'colours':>8}")
for function, r in runs.items():
    if "cpu" not in r or "cuda" not in r: continue
    cpu, gpu = r["cpu"]["real_time"], r["cuda"]["real_time"]
    kernel, copy = r["cuda"]["gpu_kernel_ms"], r["cuda"]["gpu_copy_ms"]
    solid = gpu - kernel - copy  # the solid and the rest, made on the CPU either way
    print(f"{function:22} {cpu:9.1f} {gpu:9.1f} {kernel:10.2f} {copy:9.2f} {cpu / gpu:6.1f}x "
          f"{(cpu - solid) / max(kernel, 1e-9):7.1f}x")
PY
    timeout 120 "$root/bin/coverage_cuda_test" --gtest_output="json:$results/coverage_cuda_test.json" || status=1
    timeout 60 "$root/bin/coverage_device_test" --gtest_filter='-CoverageWithoutGpu.*' \
      --gtest_output="json:$results/coverage_device_test.json" || status=1
    timeout 150 "$root/bin/coverage_device_bench" --benchmark_filter='BM_CoverageDevice/0/(512|1024)/' \
      --benchmark_min_time=0.3 --benchmark_out="$results/coverage_device_bench.json" --benchmark_out_format=json ||
      status=1
    python3 - "$results/coverage_device_bench.json" <<'PY' | tee -a "$results/speedups.txt"
import json, sys
runs = {}
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("error_occurred"):
        print("error:", b["name"], b.get("error_message")); continue
    n = b["name"].split("/")[2]
    sampling, device = b["label"].split()
    runs.setdefault((sampling, n), {})[device] = b
print(f"{'coverage':22} {'cpu ms':>9} {'gpu ms':>9} {'kernel ms':>10} {'copy ms':>9} {'whole':>7} {'kernels':>8}")
for (sampling, n), r in runs.items():
    if "cpu" not in r or "cuda" not in r: continue
    cpu, gpu = r["cpu"]["real_time"], r["cuda"]["real_time"]
    kernel, copy = r["cuda"]["gpu_kernel_ms"], r["cuda"]["gpu_copy_ms"]
    print(f"{sampling + ' ' + n + '^3':22} {cpu:9.1f} {gpu:9.1f} {kernel:10.2f} {copy:9.2f} {cpu / gpu:6.1f}x "
          f"{cpu / max(kernel, 1e-9):7.1f}x")
PY
    timeout 120 "$root/bin/sdf_cuda_test" --gtest_output="json:$results/sdf_cuda_test.json" || status=1
    timeout 60 "$root/bin/sdf_device_test" --gtest_filter='-SdfWithoutGpu.*' \
      --gtest_output="json:$results/sdf_device_test.json" || status=1
    timeout 90 "$root/bin/sdf_device_bench" --benchmark_filter='BM_SdfDevice/512/' --benchmark_min_time=0.3 \
      --benchmark_out="$results/sdf_device_bench.json" --benchmark_out_format=json || status=1
    python3 - "$results/sdf_device_bench.json" <<'PY' | tee -a "$results/speedups.txt"
import json, sys
runs = {}
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("error_occurred"):
        print("error:", b["name"], b.get("error_message")); continue
    runs[b["label"]] = b
if "cpu" in runs and "cuda" in runs:
    cpu, gpu = runs["cpu"]["real_time"], runs["cuda"]["real_time"]
    kernel, copy = runs["cuda"]["gpu_kernel_ms"], runs["cuda"]["gpu_copy_ms"]
    print(f"{'band sdf 512^3':22} {cpu:9.1f} {gpu:9.1f} {kernel:10.2f} {copy:9.2f} {cpu / gpu:6.1f}x")
PY
    scaling "$root" "$results" || status=1
    exit $status
    ;;
  scaling)
    unpack "$2" "${3:-}"
    echo "CPU threads: $(nproc)" | tee "$results/cpu.txt"
    scaling "$root" "$results"
    ;;
  *)
    sed -n '2,23p' "$0" >&2
    exit 2
    ;;
esac
