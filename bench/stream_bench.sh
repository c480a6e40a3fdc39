#!/usr/bin/env bash
# Issue #14: `voxd voxelize` of the 1.1M-triangle mesh to .rle from 1024^3 to
# 8192^3, how time and peak memory grow with N. Grids past 2^32 voxels stream
# slab by slab by themselves; --streaming on|off forces a way for every size
# (off past 4096^3 needs more memory than a 24 GB machine has: skipped).
# VOXD_BENCH_MODE=coverage measures coverage bytes instead (Thon's grey
# levels, 5 bytes a voxel in memory: off only up to 1024^3).
#   [VOXD_BENCH_MODE=solid|coverage] bench/stream_bench.sh [BUILD_DIR] [RESOLUTIONS...]
set -euo pipefail
build="${1:-build}"
shift || true
resolutions=("${@:-1024 2048 4096 8192}")
voxd="$build/server/voxd"
job_mode="${VOXD_BENCH_MODE:-solid}"
largest_off=$([[ $job_mode == coverage ]] && echo 1024 || echo 4096)
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
printf '%-6s %-10s %10s %14s %14s\n' res streaming wall_s peak_rss_MiB rle_MiB
for res in ${resolutions[@]}; do
  for mode in on off; do
    if [[ $mode == off && $res -gt $largest_off ]]; then continue; fi
    /usr/bin/time -f '%e %M' -o "$work/time" "$voxd" voxelize "$work/mesh.stl" --resolution "$res" --padding 1 \
      --mode "$job_mode" --streaming "$mode" -o "$work/out.rle" 2> /dev/null
    read -r secs kib < "$work/time"
    bytes=$(stat -c %s "$work/out.rle")
    printf '%-6s %-10s %10s %14d %14d\n' "$res" "$mode" "$secs" "$((kib / 1024))" "$((bytes >> 20))"
    rm -f "$work/out.rle"
  done
done
