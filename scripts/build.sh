#!/usr/bin/env bash
# Installs missing Debian packages, then configures and builds voxd.
#   BUILD_DIR      build folder (default: build, or build-asan with VOXD_SANITIZE=1)
#   VOXD_SANITIZE  1 = AddressSanitizer + UndefinedBehaviorSanitizer (Debug)
#   VOXD_BENCH_PEERS 1 = also build the OpenVDB/VTK comparison benchmarks
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/install-deps.sh
# The web page's npm modules (three.js, and playwright-core for its test),
# exactly as web/package-lock.json pins them; voxd embeds the page at build.
if [[ ! -f web/node_modules/.package-lock.json || web/package-lock.json -nt web/node_modules/.package-lock.json ]]; then
  (cd web && npm ci --no-audit --no-fund)
fi

build_type=Release
sanitize=OFF
if [[ "${VOXD_SANITIZE:-0}" == 1 ]]; then
  build_type=Debug
  sanitize=ON
fi
build_dir="${BUILD_DIR:-build}"
[[ "$sanitize" == ON && -z "${BUILD_DIR:-}" ]] && build_dir=build-asan

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="$build_type" -DVOXD_SANITIZE="$sanitize" -DVOXD_WERROR=ON \
  -DVOXD_BENCH_PEERS="$([[ "${VOXD_BENCH_PEERS:-0}" == 1 ]] && echo ON || echo OFF)"
cmake --build "$build_dir" -j"$(nproc)"
