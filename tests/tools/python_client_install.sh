#!/usr/bin/env bash
# The Python client installs with pip from its folder, offline (Debian's
# setuptools builds it: --no-build-isolation), into a fresh virtual
# environment, and works from outside the repository.
set -euo pipefail
source_dir="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# A copy, so the build leaves nothing in the repository.
cp -r "$source_dir/clients/python" "$work/client"
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
"$work/venv/bin/pip" install --quiet --no-build-isolation --no-index --no-deps "$work/client"
rm -rf "$work/client"
cd "$work"
"$work/venv/bin/python" - "$work/venv" <<'PY'
import sys
import voxd_client
assert voxd_client.__file__.startswith(sys.argv[1]), voxd_client.__file__
assert voxd_client.VoxdClient("http://127.0.0.1:1").server == "http://127.0.0.1:1"
from importlib.metadata import metadata
assert metadata("voxd-client")["License"] == "Apache-2.0", metadata("voxd-client")["License"]
print("installed voxd_client", voxd_client.__version__, "at", voxd_client.__file__)
PY
