#!/usr/bin/env bash
# The web page's files as a browser fetches them, from one or more voxd
# binaries in one run (to compare builds on the same machine at the same
# time): for each file, the median of REPEATS GETs with Accept-Encoding
# br, and a revalidation (If-None-Match with the ETag the first answer gave)
# of the whole page.
#   bench/page_bench.sh REPEATS VOXD_BINARY...
set -euo pipefail
repeats="${1:-5}"
shift
files=(/ /ui/js/app.js /ui/style.css /ui/vendor/three.module.js /ui/vendor/three.core.js /ui/vendor/OrbitControls.js
       /ui/vendor/redoc.standalone.js)
for voxd in "$@"; do
  work="$(mktemp -d)"
  "$voxd" serve --port 0 --data-dir "$work/data" > "$work/server.log" 2>&1 &
  server=$!
  for _ in $(seq 300); do
    port=$(grep -o 'listening on http://127.0.0.1:[0-9]*' "$work/server.log" | grep -o '[0-9]*$' || true)
    [[ -n "$port" ]] && break
    sleep 0.02
  done
  echo "== $voxd"
  printf '%-32s %12s %10s %10s\n' file bytes_sent median_s revalidate
  for f in "${files[@]}"; do
    times=()
    for _ in $(seq "$repeats"); do
      times+=("$(curl -s -o /dev/null -H 'Accept-Encoding: br' -w '%{time_total}' "http://127.0.0.1:$port$f")")
    done
    median=$(printf '%s\n' "${times[@]}" | sort -n | sed -n "$(( (repeats + 1) / 2 ))p")
    size=$(curl -s -o /dev/null -H 'Accept-Encoding: br' -w '%{size_download}' "http://127.0.0.1:$port$f")
    etag=$(curl -s -D - -o /dev/null -H 'Accept-Encoding: br' "http://127.0.0.1:$port$f" | tr -d '\r' | sed -n 's/^[Ee][Tt][Aa][Gg]: //p')
    again=$(curl -s -o /dev/null -H 'Accept-Encoding: br' ${etag:+-H "If-None-Match: $etag"} -w '%{http_code}/%{size_download}B' "http://127.0.0.1:$port$f")
    printf '%-32s %12s %10s %10s\n' "$f" "$size" "$median" "$again"
  done
  kill "$server"
  wait "$server" 2>/dev/null || true
  rm -rf "$work"
done
