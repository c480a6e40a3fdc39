#!/usr/bin/env bash
# HTTP service benchmark on loopback: the synchronous small job
# (POST /v1/voxelize, 10k-triangle mesh at 64^3) and the async flow
# (POST /v1/jobs, poll, GET volume, DELETE), throughput and latency, and the
# server's memory over a soak.
#   bench/http_bench.sh [BUILD_DIR] [SECONDS] [SOAK_SECONDS] [CONNECTIONS]
set -euo pipefail
build="${1:-build}"
seconds="${2:-20}"
soak="${3:-0}"
connections="${4:-4}"
work="$(mktemp -d)"
"$build/bench/write_bench_mesh" "$work/small.stl" --small
"$build/server/voxd" serve --port 0 --data-dir "$work/data" > "$work/server.log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null; wait $server 2>/dev/null; rm -rf "$work"' EXIT
for _ in $(seq 300); do
  port=$(grep -o 'listening on http://127.0.0.1:[0-9]*' "$work/server.log" | grep -o '[0-9]*$' || true)
  [[ -n "$port" ]] && break
  sleep 0.02
done
params='{"grid":{"resolution":64}}'
load=("$build/bench/http_load" --port "$port" --mesh "$work/small.stl" --params "$params" --server-pid "$server")
echo "mesh: 10,000 triangles ($(stat -c %s "$work/small.stl") bytes), grid 64^3, $(nproc) cores, voxd workers = cores"
"${load[@]}" --flow sync --connections 1 --seconds 3 > /dev/null  # warm-up
for c in 1 2 "$connections"; do "${load[@]}" --flow sync --connections "$c" --seconds "$seconds"; done
"${load[@]}" --flow async --connections "$connections" --seconds "$seconds"
if (( soak > 0 )); then
  echo "soak: sync flow for $soak s"
  "${load[@]}" --flow sync --connections "$connections" --seconds "$soak"
fi
