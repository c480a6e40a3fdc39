#!/usr/bin/env bash
# Whole-CLI benchmark: `voxd voxelize` of the 1.1M-triangle mesh to .rle at
# several resolutions; wall time (best of N runs) and peak resident memory.
#   bench/cli_bench.sh [BUILD_DIR] [RUNS]
set -euo pipefail
build="${1:-build}"
runs="${2:-5}"
voxd="$build/server/voxd"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
printf '%-6s %12s %12s %14s\n' res best_s median_s peak_rss_MiB
for res in 256 512 1024 2048; do
  times=()
  peak=0
  for ((r = 0; r < runs; r++)); do
    /usr/bin/time -f '%e %M' -o "$work/time" "$voxd" voxelize "$work/mesh.stl" --resolution "$res" --padding 1 \
      -o "$work/out.rle" 2> /dev/null
    read -r secs kib < "$work/time"
    times+=("$secs")
    (( kib > peak )) && peak=$kib
  done
  sorted=($(printf '%s\n' "${times[@]}" | sort -g))
  printf '%-6s %12s %12s %14d\n' "$res" "${sorted[0]}" "${sorted[$((runs / 2))]}" "$((peak / 1024))"
  rm -f "$work/out.rle"
done
# Per-stage view of one 1024^3 run.
"$voxd" voxelize "$work/mesh.stl" --resolution 1024 --padding 1 -o "$work/out.rle"
