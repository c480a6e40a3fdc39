#!/usr/bin/env bash
# The service's band SDF job, submit to succeeded, on a fresh `voxd serve`:
# 512^3 of the 1.1M-triangle benchmark mesh, three jobs (padding 2, 3, 4 so
# none is answered from another), wall time, how it ran and its timings.
#   bench/service_sdf_bench.sh VOXD MESH.stl   (MESH from build/bench/write_bench_mesh)
set -euo pipefail
voxd="$1"; mesh="$(realpath "$2")"; work=$(mktemp -d)
"$voxd" serve --port 0 --data-dir "$work/data" > "$work/log" 2>&1 & pid=$!
trap 'kill $pid; wait $pid 2>/dev/null; rm -rf $work' EXIT
for _ in $(seq 300); do port=$(grep -o 'listening on http://127.0.0.1:[0-9]*' "$work/log" | grep -o '[0-9]*$' || true); [[ -n "$port" ]] && break; sleep 0.02; done
for i in 1 2 3; do
  t0=$(date +%s.%N)
  id=$(curl -sS -F mesh=@"$mesh" -F "params={\"mode\":\"sdf\",\"grid\":{\"resolution\":512,\"padding\":$((i+1))},\"sdf\":{\"band\":3}}" http://127.0.0.1:$port/v1/jobs | python3 -c 'import sys,json;print(json.load(sys.stdin)["id"])') || true
  while :; do s=$(curl -sS http://127.0.0.1:$port/v1/jobs/$id); st=$(echo "$s" | python3 -c 'import sys,json;print(json.load(sys.stdin)["state"])'); [[ $st == succeeded || $st == failed ]] && break; sleep 0.02; done
  t1=$(date +%s.%N)
  echo "$s" | python3 -c "import sys,json;j=json.load(sys.stdin);print('$i', j['state'], 'wall %.2f s'%($t1-$t0), j.get('execution','-'), 'streamed', j['streamed'], {k:round(v,3) for k,v in j['timings'].items()})"
done
