#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz, clang with ASan+UBSan) and runs
# each one for SECONDS (default 4) on its seed corpus: the CAD-like parts the
# main build writes (BUILD/test-parts), the real STL, OBJ and PLY files of
# Debian's assimp-testmodels, Draco files made from the parts by
# draco_encoder, RLE volumes made by voxd, and the small files in
# tests/fuzz/seeds. Exits non-zero on
# the first crash, sanitizer report, out-of-memory or hang, leaving the input
# in build-fuzz/findings/. What a run learns stays in build-fuzz/corpus/.
#   scripts/fuzz.sh            the short run the test suite makes
#   scripts/fuzz.sh 600        ten minutes each (docs/security.md)
#   FUZZERS="fuzz_decode_obj" scripts/fuzz.sh 60   one of them
#   JOBS=2 runs that many fuzzers side by side (default 1)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-4}"
out=build-fuzz
main_build="${BUILD_DIR:-build}"

CC=clang CXX=clang++ cmake -S . -B "$out" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVOXD_FUZZ=ON -DVOXD_WERROR=ON >/dev/null
cmake --build "$out" -j"$(nproc)" >/dev/null

corpus="$out/corpus"
seeds="$out/seeds"
rm -rf "$seeds"
mkdir -p "$seeds"/{stl_binary,stl_ascii,obj,ply,draco,auto,job_params,analysis_query,rle,http,tenant_config,multipart} "$out/findings"
cp tests/fuzz/seeds/stl_ascii/* "$seeds/stl_ascii/"
cp tests/fuzz/seeds/obj/* "$seeds/obj/"
cp tests/fuzz/seeds/ply/* "$seeds/ply/"
cp tests/fuzz/seeds/job_params/* "$seeds/job_params/"
cp tests/fuzz/seeds/analysis_query/* "$seeds/analysis_query/"
cp tests/fuzz/seeds/http/* "$seeds/http/"
cp tests/fuzz/seeds/tenant_config/* "$seeds/tenant_config/"
cp tests/fuzz/seeds/multipart/* "$seeds/multipart/"
# Meshes small enough for a fuzzer's input length: the parts the main build
# writes (else the committed PLY box), and assimp's corpus of real files.
shopt -s nullglob
copy_small() {  # DEST FILE...
  local dest="$1" m
  shift
  for m in "$@"; do
    if [[ $(stat -c %s "$m") -le 65536 ]]; then cp "$m" "$dest/"; fi
  done
}
copy_small "$seeds/stl_binary" "$main_build"/test-parts/*.stl
assimp=/usr/share/assimp/models
copy_small "$seeds/stl_ascii" "$assimp"/STL/triangle*.stl "$assimp"/STL/sphereWithHole.stl
copy_small "$seeds/obj" "$assimp"/OBJ/*.obj
copy_small "$seeds/ply" "$assimp"/PLY/*.ply
sources=("$seeds"/stl_binary/*.stl)
((${#sources[@]})) || sources=(tests/fuzz/seeds/ply/box_le.ply)
for m in "${sources[@]}"; do
  base=$(basename "${m%.*}")
  draco_encoder -i "$m" -o "$seeds/draco/$base.drc" >/dev/null
  draco_encoder -i "$m" -o "$seeds/draco/$base-seq.drc" -cl 0 >/dev/null
  draco_encoder -i "$m" -o "$seeds/draco/$base-hi.drc" -qp 20 -cl 10 >/dev/null
done
voxd="$main_build/server/voxd"
if [[ -x "$voxd" ]]; then
  m="${sources[0]}"
  "$voxd" voxelize "$m" -o "$seeds/rle/bits.rle" --resolution 12 2>/dev/null
  "$voxd" voxelize "$m" -o "$seeds/rle/u8.rle" --mode coverage --resolution 8 2>/dev/null
  "$voxd" voxelize "$m" -o "$seeds/rle/f32.rle" --mode sdf --resolution 8 2>/dev/null
  "$voxd" voxelize "$m" -o "$seeds/rle/u16.rle" --mode sdf --resolution 8 --quantize u16 2>/dev/null
  "$voxd" voxelize "$m" -o "$seeds/rle/rgba8.rle" --mode slice --resolution 8 \
    --params '{"slice": {"function": "checker", "checker_size": 2}}' 2>/dev/null
else
  echo "fuzz: $voxd not built (scripts/build.sh): the RLE reader starts from no seed"
fi
for f in "$seeds"/{stl_binary,stl_ascii,obj,ply,draco}/*; do cp "$f" "$seeds/auto/"; done

declare -A dict=(
  [fuzz_decode_stl_ascii]=stl_ascii [fuzz_decode_obj]=obj [fuzz_decode_ply]=ply [fuzz_decode_draco]=draco
  [fuzz_job_params]=json [fuzz_analysis_query]=query [fuzz_rle_reader]=rle [fuzz_http_connection]=http
  [fuzz_tenant_config]=json [fuzz_multipart_reader]=multipart
)
declare -A seed_dir=(
  [fuzz_decode_stl_binary]=stl_binary [fuzz_decode_stl_ascii]=stl_ascii [fuzz_decode_obj]=obj
  [fuzz_decode_ply]=ply [fuzz_decode_draco]=draco [fuzz_decode_auto]=auto [fuzz_job_params]=job_params
  [fuzz_analysis_query]=analysis_query [fuzz_rle_reader]=rle [fuzz_http_connection]=http
  [fuzz_tenant_config]=tenant_config [fuzz_multipart_reader]=multipart
)
fuzzers="${FUZZERS:-fuzz_decode_stl_binary fuzz_decode_stl_ascii fuzz_decode_obj fuzz_decode_ply fuzz_decode_draco fuzz_decode_auto fuzz_job_params fuzz_analysis_query fuzz_rle_reader fuzz_http_connection fuzz_tenant_config fuzz_multipart_reader}"

run_one() {
  local f="$1" log="$out/findings/$1.log"
  mkdir -p "$corpus/$f"
  local args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=65536
              -print_final_stats=1 -artifact_prefix="$out/findings/$f-")
  [[ -n "${dict[$f]:-}" ]] && args+=(-dict="tests/fuzz/dict/${dict[$f]}.dict")
  if ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     "$out/tests/fuzz/$f" "${args[@]}" "$corpus/$f" "$seeds/${seed_dir[$f]}" >"$log" 2>&1; then
    echo "fuzz: $f ok: $(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$') runs in ${seconds} s, corpus $(ls "$corpus/$f" | wc -l)"
  else
    echo "fuzz: $f FAILED (log $log):"
    # What the harness said before it stopped (its own check's message, or
    # the sanitizer's report), and the input itself where libFuzzer prints
    # it: a CI log is all there is of a clean clone's run.
    local first
    first=$(grep -n -m1 -E "deadly signal|ERROR: |runtime error|==[0-9]+==" "$log" | cut -d: -f1 || true)
    if [[ -n "$first" ]]; then sed -n "$((first > 12 ? first - 12 : 1)),$((first + 40))p" "$log"; else tail -n 40 "$log"; fi
    grep -E "^Base64: |Test unit written" "$log" | head -2
    return 1
  fi
}

failed=0
jobs_n="${JOBS:-1}"
running=0
for f in $fuzzers; do
  if ((jobs_n > 1)); then
    run_one "$f" & running=$((running + 1))
    if ((running >= jobs_n)); then wait -n || failed=1; running=$((running - 1)); fi
  else
    run_one "$f" || failed=1
  fi
done
while ((running > 0)); do wait -n || failed=1; running=$((running - 1)); done
exit "$failed"
