#!/usr/bin/env bash
# Scale-out benchmark on loopback: the async small-job flow (POST /v1/jobs,
# poll, GET volume, DELETE; 10k triangles at 64^3) against the embedded
# service, one replica on Redis (the shared queue's cost per job) and three
# replicas on the same Redis (connections spread over them). Then one huge
# job: embedded, and split into slab tasks over one and over three replicas.
#   bench/scale_out_bench.sh [BUILD_DIR] [SECONDS] [CONNECTIONS]
set -euo pipefail
build="${1:-build}"
seconds="${2:-20}"
connections="${3:-4}"
work="$(mktemp -d)"
pids=()
cleanup() {
  stop_voxd 2>/dev/null || true
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
"$build/bench/write_bench_mesh" "$work/small.stl" --small
: > "$work/voxd.pids"
redis_port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
redis-server --port "$redis_port" --bind 127.0.0.1 --dir "$work" --appendonly yes --appendfsync everysec --save "" \
  --logfile "$work/redis.log" --daemonize no &
pids+=($!)
for _ in $(seq 200); do redis-cli -p "$redis_port" ping > /dev/null 2>&1 && break; sleep 0.02; done

# Starts `voxd serve ARGS...`; prints its port. (It runs in a command
# substitution, a subshell: its pid goes to a file, not to a variable.)
serve() {
  local n
  n=$(wc -l < "$work/voxd.pids")
  local log="$work/voxd-$n.log"
  "$build/server/voxd" serve --port 0 --data-dir "$work/data-$n" "$@" > "$log" 2>&1 &
  echo $! >> "$work/voxd.pids"
  for _ in $(seq 300); do
    port=$(grep -o 'listening on http://127.0.0.1:[0-9]*' "$log" | grep -o '[0-9]*$' || true)
    [[ -n "$port" ]] && { echo "$port"; return; }
    sleep 0.02
  done
  echo "voxd did not start: $(cat "$log")" >&2
  exit 1
}
stop_voxd() {  # every voxd started so far
  while read -r p; do kill "$p" 2>/dev/null || true; done < "$work/voxd.pids"
  : > "$work/voxd.pids"
  sleep 0.5
  redis-cli -p "$redis_port" flushall > /dev/null
}
params='{"grid":{"resolution":64}}'
load() { "$build/bench/http_load" --mesh "$work/small.stl" --params "$params" --flow async --seconds "$seconds" "$@"; }
echo "mesh: 10,000 triangles, grid 64^3, async flow, $(nproc) cores, $connections connections, $seconds s each"

echo "== embedded (workers = cores)"
port=$(serve)
load --port "$port" --connections 1 --seconds 3 > /dev/null  # warm-up
load --port "$port" --connections 1
load --port "$port" --connections "$connections"
stop_voxd

echo "== one replica on Redis (workers = cores)"
port=$(serve --redis "redis://127.0.0.1:$redis_port")
load --port "$port" --connections 1 --seconds 3 > /dev/null
load --port "$port" --connections 1
load --port "$port" --connections "$connections"
stop_voxd

echo "== three replicas on Redis (workers = cores each), connections spread over them"
ports=$(serve --redis "redis://127.0.0.1:$redis_port"),$(serve --redis "redis://127.0.0.1:$redis_port"),$(serve --redis "redis://127.0.0.1:$redis_port")
load --port "$ports" --connections 3 --seconds 3 > /dev/null
load --port "$ports" --connections "$connections"
stop_voxd

# One huge job (the benchmark torus, 1.1 M triangles, at 3000 voxels along
# its longest axis: 3000 x 2902 x 2271, 19.8 G voxels, 2.5 GB of bits, made
# slab by slab):
# seconds from POST to succeeded, then its RLE fetched and compared with
# the first run's.
"$build/bench/write_bench_mesh" "$work/big.stl"
huge_params='{"grid":{"resolution":3000},"streaming":"on"}'
huge() {  # PORT LABEL
  local t0 id state
  t0=$(date +%s.%N)
  id=$(curl -sf -F "mesh=@$work/big.stl" -F "params=$huge_params" "http://127.0.0.1:$1/v1/jobs" | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')
  while :; do
    state=$(curl -sf "http://127.0.0.1:$1/v1/jobs/$id" | python3 -c 'import json,sys; print(json.load(sys.stdin)["state"])')
    [[ "$state" == queued || "$state" == running ]] || break
    sleep 0.05
  done
  printf '%s: %s in %s s' "$2" "$state" "$(python3 -c "print(round($(date +%s.%N) - $t0, 2))")"
  curl -sf -o "$work/huge-$2.rle" "http://127.0.0.1:$1/v1/jobs/$id/volume"
  if [[ -f "$work/huge-first.rle" ]]; then
    cmp -s "$work/huge-first.rle" "$work/huge-$2.rle" && echo " (same bytes)" || echo " (DIFFERENT BYTES)"
  else
    mv "$work/huge-$2.rle" "$work/huge-first.rle"
    echo " ($(stat -c %s "$work/huge-first.rle") bytes of RLE)"
  fi
}
echo "== one huge job: 1.1 M triangles at resolution 3000, streamed; split into slab tasks of 1 GiB of bits (the default) with Redis"
huge "$(serve)" embedded
stop_voxd
redis="redis://127.0.0.1:$redis_port"
huge "$(serve --redis "$redis" --max-result-bytes 0)" one-replica
stop_voxd
ports=("$(serve --redis "$redis" --max-result-bytes 0)" "$(serve --redis "$redis" --max-result-bytes 0)" "$(serve --redis "$redis" --max-result-bytes 0)")
huge "${ports[0]}" three-replicas
echo "slab tasks made per replica: $(for f in "$work"/voxd-*.log; do grep -c 'slab task .* done' "$f" || true; done | tr '\n' ' ')"
