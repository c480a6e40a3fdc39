#!/usr/bin/env bash
# Whole-CLI benchmark of the value modes: `voxd voxelize` of the 1.1M-triangle
# benchmark mesh as coverage (4 x 4 rays, u8), as a signed distance field
# (band of 3 voxels), as a palette voxelization (46 elements, nearest, t = 16,
# p = 4) and as a slice voxelization (marble) to each output format; wall
# time (best of N runs), peak resident memory and output size.
#   bench/value_cli_bench.sh [BUILD_DIR] [RUNS] [MODES]
# MODES: any of "coverage sdf palette slice" (default: all).
set -euo pipefail
build="${1:-build}"
runs="${2:-3}"
modes="${3:-coverage sdf palette slice}"
want() { [[ " $modes " == *" $1 "* ]]; }
voxd="$build/server/voxd"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
printf '%-44s %-5s %10s %14s %12s\n' job res best_s peak_rss_MiB output_MiB
run() {  # name, resolution, output file name, voxd flags...
  local name="$1" res="$2" out="$work/$3"
  shift 3
  local best="" peak=0
  for ((r = 0; r < runs; r++)); do
    /usr/bin/time -f '%e %M' -o "$work/time" "$voxd" voxelize "$work/mesh.stl" --resolution "$res" -o "$out" "$@" 2> /dev/null
    read -r secs kib < "$work/time"
    if [[ -z "$best" ]] || awk "BEGIN{exit !($secs < $best)}"; then best=$secs; fi
    (( kib > peak )) && peak=$kib
  done
  printf '%-44s %-5s %10s %14d %12d\n' "$name" "$res" "$best" "$((peak / 1024))" "$(( $(stat -c %s "$out") >> 20 ))"
  rm -f "$out"
}
palette='{"mode":"palette","palette":{"elements":46,"metric":"nearest","rays":16,"points":4}}'
marble='{"mode":"slice","slice":{"function":"marble"}}'
for res in 256 512; do
  if want coverage; then
    run "coverage exact 4x4, u8 rle" "$res" c.rle --padding 1 --mode coverage
    run "coverage exact 4x4, u8 binvox" "$res" c.binvox --padding 1 --mode coverage
  fi
  if want sdf; then
    run "sdf band 3, f32 nrrd" "$res" d.nrrd --padding 3 --mode sdf
    run "sdf band 3, f32 rle" "$res" d.rle --padding 3 --mode sdf
    run "sdf band 3, u16 rle (quantized)" "$res" q.rle --padding 3 --mode sdf --quantize u16
  fi
  if want palette; then
    run "palette 46 nearest, element rle" "$res" p.rle --padding 1 --params "$palette"
    run "palette 46 nearest, glb (instanced)" "$res" p.glb --padding 1 --params "$palette"
    run "palette 46 nearest, stl" "$res" p.stl --padding 1 --params "$palette"
  fi
  if want slice; then
    run "slice marble, rgba8 rle" "$res" s.rle --padding 1 --params "$marble"
    run "slice marble, vox" "$res" s.vox --padding 1 --params "$marble"
    run "slice marble, png-stack zip" "$res" s.zip --padding 1 --params "$marble"
  fi
done
