#!/usr/bin/env bash
# Installs what is missing, builds, and starts the voxd HTTP service with its
# embedded defaults: http://127.0.0.1:8080, jobs kept in ./voxd-data.
# Every default can be changed by flag or VOXD_* variable: `voxd serve --help`.
# Example: VOXD_HOST=0.0.0.0 VOXD_PORT=9000 ./scripts/start.sh
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/build.sh
exec build/server/voxd serve "$@"
