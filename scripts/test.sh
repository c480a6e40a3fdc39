#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (unit, integration, schema),
# after a short run of every fuzzer (scripts/fuzz.sh, about 4 s each).
# VOXD_SANITIZE=1 runs it under AddressSanitizer + UndefinedBehaviorSanitizer.
#   VOXD_FUZZ_SECONDS=N runs each fuzzer N seconds (0 skips them).
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/build.sh
build_dir="${BUILD_DIR:-build}"
[[ "${VOXD_SANITIZE:-0}" == 1 && -z "${BUILD_DIR:-}" ]] && build_dir=build-asan
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
fuzz_seconds="${VOXD_FUZZ_SECONDS:-4}"
if [[ "$fuzz_seconds" != 0 ]]; then
  BUILD_DIR="$build_dir" ./scripts/fuzz.sh "$fuzz_seconds"
fi
cd "$build_dir"
# The CUDA kernels' tests (label gpu) need a GPU; without one their host
# side is tested by the core tests.
exclude=()
if ! nvidia-smi -L >/dev/null 2>&1; then
  echo "test.sh: no GPU (nvidia-smi finds none): the gpu-labelled tests are left out"
  exclude=(-LE gpu)
fi
ctest --output-on-failure -j"$(nproc)" --timeout 900 "${exclude[@]}"
