#!/usr/bin/env bash
# Issue #39's acceptance in the service: the 1.1M-triangle mesh as a solid
# job at N^3 (default 512, padding 2), then the full report (mass
# properties, parts, voids, skin, wall thickness with thin and thick
# regions) and, after it, the thickness volume, which answers from the map
# the report kept. Prints the seconds of each step as the client sees them,
# and the server's peak RSS (VmHWM) after each, also in bytes per voxel of
# the grid.
#   bench/report_service_bench.sh [BUILD_DIR] [RESOLUTION]
#   THREADS  the server's --threads (default: its own default, every core)
#   KEEP     a folder to copy analysis.json and thickness.nrrd into (to
#            compare two builds' bytes)
#   LOG      a file to copy the server's log into (its stage timings)
set -euo pipefail
build="${1:-build}"
res="${2:-512}"
voxd="$build/server/voxd"
work="$(mktemp -d)"
server=""
cleanup() {
  [[ -n "$server" ]] && kill "$server" 2> /dev/null && wait "$server" 2> /dev/null || true
  [[ -n "${LOG:-}" ]] && cp "$work/log" "$LOG"
  rm -rf "$work"
}
trap cleanup EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
source "$(dirname "$0")/service_lib.sh"
start_voxd "$voxd" "${threads[@]}"
voxels=1
peak() { awk '/VmHWM/ {print $2 * 1024}' "/proc/$server/status"; }
now() { date +%s.%N; }
step() {  # name, seconds since $1
  local bytes
  bytes=$(peak)
  printf '%-44s %7.2f s   server peak RSS %6d MiB (%5.1f bytes a voxel)\n' "$1" "$(echo "$(now) - $2" | bc)" \
    "$((bytes >> 20))" "$(echo "$bytes / $voxels" | bc -l)"
}

t0=$(now)
run_job "$work/mesh.stl" "{\"grid\":{\"resolution\":$res,\"padding\":2}}"
voxels=$(python3 -c 'import json,sys; d=json.loads(sys.argv[1])["grid"]["dims"]; print(d[0]*d[1]*d[2])' "$status")
python3 -c 'import json,sys; s=json.loads(sys.argv[1]); print("job: grid", s["grid"]["dims"], "filled", s["filled_voxels"])' "$status"
step "job (upload to succeeded)" "$t0"
t0=$(now)
curl -sf "$url/v1/jobs/$id/analysis?min_wall=0.02&max_wall=0.5" -o "$work/analysis.json"
step "GET /analysis (full report)" "$t0"
python3 - "$work/analysis.json" << 'EOF'
import json, sys
a = json.load(open(sys.argv[1]))
t = a["thickness"]
print("  parts", a["parts"]["count"], "voids", a["voids"]["count"], "skin layers", len(a.get("skin", {}).get("layers", [])),
      "thin regions", len(t.get("thin_regions", [])), "thick regions", len(t.get("thick_regions", [])))
EOF
t0=$(now)
curl -sf "$url/v1/jobs/$id/thickness?format=nrrd" -o "$work/thickness.nrrd"
step "GET /thickness?format=nrrd ($(($(wc -c < "$work/thickness.nrrd") >> 20)) MiB, kept)" "$t0"
if [[ -n "${KEEP:-}" ]]; then
  mkdir -p "$KEEP"
  cp "$work/analysis.json" "$work/thickness.nrrd" "$KEEP/"
fi
