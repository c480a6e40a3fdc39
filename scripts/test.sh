#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (unit, integration, schema).
# VOXD_SANITIZE=1 runs it under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/build.sh
build_dir="${BUILD_DIR:-build}"
[[ "${VOXD_SANITIZE:-0}" == 1 && -z "${BUILD_DIR:-}" ]] && build_dir=build-asan
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" --timeout 900
