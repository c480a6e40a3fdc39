#!/usr/bin/env bash
# The installed-package check (ctest install.consumer):
#   install_consumer_test.sh BUILD_DIR WORK_DIR CONSUMER_SOURCE
# installs BUILD_DIR into WORK_DIR/prefix, configures and builds the consumer
# project against it alone (CMAKE_PREFIX_PATH), and runs it on a 3 x 2 x 1.5
# box at 0.25: every one of the 12 x 8 x 6 voxels inside, volume exactly 9.
set -euo pipefail
build="$1" work="$2" source="$3"
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
# Nothing internal is installed: the detail headers stay in the tree.
if [[ -e "$work/prefix/include/voxd/detail" ]]; then
  echo "FAIL: voxd/detail/ was installed" >&2
  exit 1
fi
# The umbrella header includes every installed public header, and names
# nothing that is not installed.
installed="$(cd "$work/prefix/include" && find voxd -name '*.h' ! -path voxd/voxd.h | sort)"
umbrella="$(sed -n 's/^#include "\(voxd\/[^"]*\)"$/\1/p' "$work/prefix/include/voxd/voxd.h" | sort)"
if [[ "$installed" != "$umbrella" ]]; then
  echo "FAIL: voxd/voxd.h and the installed headers differ (< installed, > included):" >&2
  diff <(echo "$installed") <(echo "$umbrella") >&2 || true
  exit 1
fi
# The package names its license, and its text comes with it.
if ! grep -q 'set(voxd_LICENSE "Apache-2.0")' "$(find "$work/prefix" -name voxdConfig.cmake)"; then
  echo "FAIL: voxdConfig.cmake does not name the license" >&2
  exit 1
fi
if ! cmp -s "$source/../../../LICENSE" "$work/prefix/share/doc/voxd/LICENSE"; then
  echo "FAIL: the LICENSE was not installed as share/doc/voxd/LICENSE" >&2
  exit 1
fi
cmake -S "$source" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" > "$work/configure.log"
cmake --build "$work/build" > "$work/build.log"
python3 - "$work/box.stl" <<'PY'
import sys
x, y, z = 3.0, 2.0, 1.5
v = [(0, 0, 0), (x, 0, 0), (x, y, 0), (0, y, 0), (0, 0, z), (x, 0, z), (x, y, z), (0, y, z)]
faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
         (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
with open(sys.argv[1], "w") as f:
    f.write("solid box\n")
    for t in faces:
        f.write(" facet normal 0 0 0\n  outer loop\n")
        for i in t:
            f.write("   vertex %g %g %g\n" % v[i])
        f.write("  endloop\n endfacet\n")
    f.write("endsolid box\n")
PY
out="$("$work/build/voxd_consumer" "$work/box.stl" 0.25)"
echo "$out"
expected=$'triangles 12\nfilled 576\nmesh_volume 9.000000'
if [[ "$out" != "$expected" ]]; then
  echo "FAIL: expected:" >&2
  echo "$expected" >&2
  exit 1
fi
echo "PASS: find_package(voxd) -> voxd::core, built outside the tree, voxelized the box exactly"

# The engine alone as a shared library (VOXD_LIBRARY_ONLY, BUILD_SHARED_LIBS),
# as a CAD plugin's host would load it: the same consumer, the same answer,
# through libvoxd_core.so, and no Embree anywhere.
root="$source/../../.."
cmake -S "$root" -B "$work/shared-build" -DVOXD_LIBRARY_ONLY=ON -DBUILD_SHARED_LIBS=ON \
  -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" > "$work/shared-configure.log"
cmake --build "$work/shared-build" -j"$(nproc)" > "$work/shared-build.log"
cmake --install "$work/shared-build" --prefix "$work/shared-prefix" > "$work/shared-install.log"
cmake -S "$source" -B "$work/shared-consumer" -DCMAKE_PREFIX_PATH="$work/shared-prefix" \
  -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" > "$work/shared-consumer-configure.log"
cmake --build "$work/shared-consumer" > "$work/shared-consumer-build.log"
out="$(LD_LIBRARY_PATH="$work/shared-prefix/lib" "$work/shared-consumer/voxd_consumer" "$work/box.stl" 0.25)"
if [[ "$out" != "$expected" ]]; then
  echo "FAIL: the consumer of the shared engine printed:" >&2
  echo "$out" >&2
  exit 1
fi
libs="$(LD_LIBRARY_PATH="$work/shared-prefix/lib" ldd "$work/shared-consumer/voxd_consumer")"
if ! grep -q "libvoxd_core.so => $work/shared-prefix/lib/" <<< "$libs"; then
  echo "FAIL: the consumer does not load the installed libvoxd_core.so:" >&2
  echo "$libs" >&2
  exit 1
fi
if grep -qi embree <<< "$libs"; then
  echo "FAIL: the engine still loads Embree:" >&2
  echo "$libs" >&2
  exit 1
fi
echo "PASS: BUILD_SHARED_LIBS: the consumer loads libvoxd_core.so, without Embree, with the same answer"
