#!/usr/bin/env bash
# Issue #14 in the service: the 1.1M-triangle mesh as a solid job over HTTP
# at N^3 (default 8192), streamed into its stored RLE, then its /volume, a
# radiography along z, its mass properties (analysis with
# thickness=false&skin=false) and shaded previews, each timed, and local
# thickness, which must answer 422. Prints the seconds of each step and the
# server's peak RSS (VmHWM) after each.
#   bench/stream_service_bench.sh [BUILD_DIR] [RESOLUTION]
#   STEPS   the steps after the job, of: volume radiography analysis section
#           preview thickness (default: all)
#   KEEP    a folder to copy the analysis report, the radiographs and the
#           sections and previews into (analysis.json, z.png, x.json, y.png,
#           section-{z,x,y}.png, top.png, side.png), to compare two builds'
#           bytes
set -euo pipefail
build="${1:-build}"
res="${2:-8192}"
steps=" ${STEPS:-volume radiography analysis section preview thickness} "
want() { [[ "$steps" == *" $1 "* ]]; }
voxd="$build/server/voxd"
work="$(mktemp -d)"
server=""
cleanup() {
  [[ -n "$server" ]] && kill "$server" 2> /dev/null && wait "$server" 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
source "$(dirname "$0")/service_lib.sh"
start_voxd "$voxd"
peak() { awk '/VmHWM/ {print int($2 / 1024)}' "/proc/$server/status"; }
now() { date +%s.%N; }
step() {  # name, seconds since $1
  printf '%-34s %8.2f s   server peak RSS %6d MiB\n' "$1" "$(echo "$(now) - $2" | bc)" "$(peak)"
}

t0=$(now)
run_job "$work/mesh.stl" "{\"grid\":{\"resolution\":$res,\"padding\":1}}"
python3 -c 'import json,sys; s=json.loads(sys.argv[1]); print("job: grid", s["grid"]["dims"], "streamed", s["streamed"], "filled", s["filled_voxels"])' "$status"
step "job (upload to succeeded)" "$t0"
if want volume; then
  t0=$(now); bytes=$(curl -sf "$url/v1/jobs/$id/volume" | wc -c); step "GET /volume rle ($((bytes >> 20)) MiB)" "$t0"
fi
# (nrrd and raw stream too, but at 8192^3 they are 512 GiB of bytes or 64 GiB
# of bits to send: minutes of transfer, not a measure of the service.)
if want radiography; then
  t0=$(now); curl -sf "$url/v1/jobs/$id/radiography?axis=z&measure=max" -o "$work/z.png"; step "radiography z (png16)" "$t0"
  t0=$(now); curl -sf "$url/v1/jobs/$id/radiography?axis=x&measure=total&format=json" -o "$work/x.json"; step "radiography x (json)" "$t0"
  t0=$(now); curl -sf "$url/v1/jobs/$id/radiography?axis=y&measure=min" -o "$work/y.png"; step "radiography y (png16)" "$t0"
  [[ -n "${KEEP:-}" ]] && cp "$work/z.png" "$work/x.json" "$work/y.png" "$KEEP/"
fi
if want analysis; then
  t0=$(now); curl -sf "$url/v1/jobs/$id/analysis?thickness=false&skin=false" -o "$work/analysis.json"; step "mass properties, parts, voids" "$t0"
  python3 -c 'import json,sys; a=json.load(open(sys.argv[1])); print("  volume", a["mass_properties"]["voxels"]["volume"], "parts", a["parts"]["count"], "voids", a["voids"]["count"])' "$work/analysis.json"
  [[ -n "${KEEP:-}" ]] && cp "$work/analysis.json" "$KEEP/analysis.json"
fi
if want section; then
  for axis in z x y; do
    index=$(python3 -c 'import json,sys; s=json.loads(sys.argv[1]); print(s["grid"]["dims"]["xyz".index(sys.argv[2])] // 2)' "$status" $axis)
    t0=$(now); curl -sf "$url/v1/jobs/$id/section?axis=$axis&index=$index" -o "$work/section-$axis.png"; step "section $axis (middle layer)" "$t0"
    [[ -n "${KEEP:-}" ]] && cp "$work/section-$axis.png" "$KEEP/"
  done
fi
if want preview; then
  t0=$(now); curl -sf "$url/v1/jobs/$id/preview?view=%2Bz" -o "$work/top.png"; step "preview +z (two passes)" "$t0"
  t0=$(now); curl -sf "$url/v1/jobs/$id/preview?view=-x" -o "$work/side.png"; step "preview -x (two passes)" "$t0"
  for png in top side; do
    [[ -n "${KEEP:-}" ]] && cp "$work/$png.png" "$KEEP/$png.png"
    python3 -c 'import struct,sys; d=open(sys.argv[1],"rb").read(); w,h=struct.unpack(">II",d[16:24]); print(f"  {sys.argv[2]}: {w} x {h} pixels, {len(d)/2**20:.1f} MiB")' "$work/$png.png" "$png"
  done
fi
if want thickness; then
  code=$(curl -s -o "$work/problem.json" -w '%{http_code}' "$url/v1/jobs/$id/thickness")
  echo "local thickness: HTTP $code: $(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["detail"])' "$work/problem.json")"
  [[ $code == 422 ]]
fi
