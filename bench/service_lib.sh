# Sourced by the service benchmarks (bench/*_service_bench.sh): starts
# `voxd serve` on a loopback ephemeral port and runs a job to its end, as a
# client does. The caller sets `work` (a scratch folder) and kills "$server"
# when done.

# start_voxd VOXD [SERVE_ARGS...]: sets `server` (its pid) and `url`.
start_voxd() {
  local voxd="$1"
  shift
  "$voxd" serve --host 127.0.0.1 --port 0 --data-dir "$work/data" "$@" > "$work/log" 2>&1 &
  server=$!
  local port=""
  for _ in $(seq 100); do
    port=$(grep -o 'listening on [^ ]*:[0-9]*' "$work/log" | grep -o '[0-9]*$' || true)
    [[ -n "$port" ]] && break
    sleep 0.1
  done
  [[ -n "$port" ]] || { cat "$work/log"; exit 1; }
  url="http://127.0.0.1:$port"
}

# run_job MESH PARAMS_JSON: submits the mesh and polls until the job ends;
# sets `id` and `status` (its last JSON), and exits unless it succeeded.
run_job() {
  id=$(curl -sf -F "mesh=@$1" -F "params=$2" "$url/v1/jobs" | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')
  local state
  while :; do
    status=$(curl -sf "$url/v1/jobs/$id")
    state=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["state"])' "$status")
    [[ $state == succeeded || $state == failed || $state == cancelled ]] && break
    sleep 0.2
  done
  [[ $state == succeeded ]] || { echo "job $state: $status"; exit 1; }
}
