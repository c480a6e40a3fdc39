#!/usr/bin/env bash
# Installs, builds, and runs voxd with its embedded defaults.
# The HTTP service (`voxd serve`) is the next milestone; until it lands this
# voxelizes a sample mesh with the command-line tool and inspects it.
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/build.sh
voxd=build/server/voxd
sample=../shared/meshes/bunny.stl
out="${TMPDIR:-/tmp}/voxd-sample"
mkdir -p "$out"
if [[ ! -f "$sample" ]]; then
  # No shared meshes next to this checkout: make a tiny ASCII STL tetrahedron.
  sample="$out/tetrahedron.stl"
  cat > "$sample" <<'STL'
solid tetra
facet normal 0 0 -1
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 1 0 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 0 1
endloop
endfacet
facet normal -1 0 0
outer loop
vertex 0 0 0
vertex 0 0 1
vertex 0 1 0
endloop
endfacet
facet normal 1 1 1
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid tetra
STL
fi
"$voxd" inspect "$sample"
"$voxd" voxelize "$sample" --resolution 128 --padding 1 -o "$out/sample.rle"
"$voxd" voxelize "$sample" --resolution 128 --padding 1 -o "$out/sample.binvox"
echo "voxd: wrote $out/sample.rle and $out/sample.binvox"
