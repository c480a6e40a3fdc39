#!/usr/bin/env bash
# Issue #40's interaction in the service: the 1.1M-triangle mesh as a solid
# job at N^3 (default 512, padding 2), then a slice function's parameter
# "dragged" over STEPS values (each a new function, so each a miss): for
# each, GET the section through the middle and the +z preview coloured by
# it (colour=slice), on one kept-alive connection as a page does. Prints
# each image's milliseconds (median, 90th percentile, max) as the client
# sees them, and, for scale, the slice job that makes the whole volume.
#   bench/slice_editing_service_bench.sh [BUILD_DIR] [RESOLUTION]
#   FUNCTION  marble (default), wood, rock, checker or color_ramp
#   STEPS     values dragged over (default 20)
#   THREADS   the server's --threads (default: every core)
set -euo pipefail
build="${1:-build}"
res="${2:-512}"
voxd="$build/server/voxd"
work="$(mktemp -d)"
server=""
cleanup() {
  [[ -n "$server" ]] && kill "$server" 2> /dev/null && wait "$server" 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
"$build/bench/write_bench_mesh" "$work/mesh.stl"
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
source "$(dirname "$0")/service_lib.sh"
start_voxd "$voxd" "${threads[@]}"
grid="{\"resolution\":$res,\"padding\":2}"
run_job "$work/mesh.stl" "{\"grid\":$grid}"
echo "solid job: grid $(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["grid"]["dims"])' "$status"), $(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["filled_voxels"])' "$status") filled"
python3 - "$url" "$id" "${FUNCTION:-marble}" "${STEPS:-20}" "$status" << 'PY'
import http.client, json, statistics, sys, time, urllib.parse
url, job, function, steps, status = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), json.loads(sys.argv[5])
host, port = urllib.parse.urlparse(url).hostname, urllib.parse.urlparse(url).port
conn = http.client.HTTPConnection(host, port)
mid = status["grid"]["dims"][2] // 2
def options(t):  # the dragged parameter at t in [0, 1]
    if function in ("marble", "wood"):
        return {"function": function, "period": round(0.2 + 0.8 * t, 4), "turbulence": 1.5}
    if function == "rock":
        return {"function": "rock", "noise_scale": round(0.05 + 0.5 * t, 4)}
    if function == "checker":
        return {"function": "checker", "checker_size": round(0.05 + 0.3 * t, 4)}
    return {"function": "color_ramp", "ramp": [{"position": 0, "color": "#0000ff"}, {"position": round(0.1 + 0.8 * t, 4), "color": "#ffffff"}, {"position": 1, "color": "#ff0000"}]}
def get(path):
    t0 = time.perf_counter()
    conn.request("GET", path)
    r = conn.getresponse()
    body = r.read()
    ms = (time.perf_counter() - t0) * 1000
    if r.status != 200 or r.getheader("X-Voxd-Cache") != "miss":
        sys.exit(f"{path}: {r.status} {r.getheader('X-Voxd-Cache')} {body[:200]}")
    return ms
times = {"section": [], "preview": []}
for s in range(steps):
    q = urllib.parse.quote(json.dumps(options(s / max(1, steps - 1))), safe="")
    times["section"].append(get(f"/v1/jobs/{job}/section?axis=z&index={mid}&colour=slice&slice={q}"))
    times["preview"].append(get(f"/v1/jobs/{job}/preview?view=%2Bz&colour=slice&slice={q}"))
for name, t in times.items():
    t.sort()
    print(f"{function} {name:8s} {len(t)} updates: median {statistics.median(t):6.1f} ms, "
          f"p90 {t[int(0.9 * (len(t) - 1))]:6.1f} ms, max {t[-1]:6.1f} ms")
both = [a + b for a, b in zip(times["section"], times["preview"])]
print(f"{function} section + preview: median {statistics.median(both):6.1f} ms an update")
PY
slice_options=$(python3 -c 'import json,sys; f=sys.argv[1]; print(json.dumps({"function": f, "period": 0.5, "turbulence": 1.5} if f in ("marble","wood") else {"function": f}))' "${FUNCTION:-marble}")
t0=$(date +%s.%N)
run_job "$work/mesh.stl" "{\"grid\":$grid,\"mode\":\"slice\",\"slice\":$slice_options}"
printf 'the slice job (upload to succeeded, the whole volume): %.2f s\n' "$(echo "$(date +%s.%N) - $t0" | bc)"
