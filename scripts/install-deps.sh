#!/usr/bin/env bash
# Installs every Debian 12 package voxd needs to build, test and benchmark.
# Idempotent: only calls apt-get when something is missing. Run as root.
#   --runtime         only what the built `voxd` needs to run (the container's
#                     final stage); a test checks it against ldd of the binary
#   --print-runtime   print that list and exit
set -euo pipefail

runtime_packages=(
  libc6 libgcc-s1 libstdc++6 libcpp-httplib0.11 libdraco7 libfmt9 libspdlog1.10 libssl3 libbrotli1 zlib1g
  libembree3-3 libpng16-16 libhiredis0.14 curl
)
if [[ "${1:-}" == --print-runtime ]]; then
  printf '%s\n' "${runtime_packages[@]}"
  exit 0
fi

packages=(
  build-essential cmake pkg-config git ca-certificates curl
  libembree-dev libglm-dev libcpp-httplib-dev nlohmann-json3-dev
  libdraco-dev draco libspdlog-dev libfmt-dev libpng-dev zlib1g-dev libssl-dev
  libbrotli-dev  # the web page's files are brotli-compressed at build time (server/web_build/)
  libgtest-dev libgmock-dev libbenchmark-dev
  libhiredis-dev redis-server
  assimp-testmodels  # real STL/OBJ/PLY files the decoder and open-mesh tests read
  python3 python3-numpy python3-jsonschema python3-yaml python3-venv python3-pip python3-setuptools
  clang libclang-rt-14-dev util-linux
  systemd  # systemd-analyze verifies deploy/systemd/voxd.service (tests/tools/check_deploy.py)
  docker-compose  # docker-compose config reads deploy/compose.yaml as Docker would (tests/tools/check_deploy.py)
  chromium
  poppler-utils  # pdfinfo and pdftotext read the report Chromium prints to PDF (tests/web/browser_test.mjs)
)
if [[ "${1:-}" == --runtime ]]; then
  packages=("${runtime_packages[@]}")
elif [[ "${VOXD_INSTALL_PEERS:-0}" == 1 ]]; then
  packages+=(libopenvdb-dev libvtk9-dev libtbb-dev)
fi

missing=()
# The web page's modules and the browser test's driver come from npm (web/
# package-lock.json): Node.js and npm from Debian unless a node is already
# installed (NodeSource's nodejs carries its own npm and conflicts with
# Debian's npm package).
if [[ "${1:-}" != --runtime ]] && ! { command -v node && command -v npm; } >/dev/null 2>&1; then
  missing+=(nodejs npm)
fi
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  [[ $(id -u) -eq 0 ]] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all packages present"
fi
