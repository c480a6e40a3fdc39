// libFuzzer harness for one mesh decoder (VOXD_FUZZ_FORMAT, a MeshFormat
// name) or, with "auto", detection plus decode_mesh. Every input must either
// throw voxd::Error or give a mesh the engine can use: indices in range, no
// repeated index, finite coordinates, at least one triangle. Anything else
// (a crash, a sanitizer report, an out-of-memory or a hang) is a finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string_view>

#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace {

constexpr std::string_view kFormat = VOXD_FUZZ_FORMAT;

voxd::MeshFormat format_of(std::string_view name) {
  for (auto f : {voxd::MeshFormat::stl_binary, voxd::MeshFormat::stl_ascii, voxd::MeshFormat::obj,
                 voxd::MeshFormat::ply, voxd::MeshFormat::draco})
    if (name == voxd::to_string(f)) return f;
  return voxd::MeshFormat::unknown;
}

void check(const voxd::Mesh& mesh) {
  if (mesh.triangles.empty()) std::abort();
  for (const auto& v : mesh.vertices)
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) std::abort();
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t i : t)
      if (i >= mesh.vertices.size()) std::abort();
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  voxd::DecodeLimits limits;
  limits.max_bytes = 1 << 20;
  limits.max_triangles = 1'000'000;  // the service's limit is larger; the checks scale with it
  const std::span<const std::uint8_t> bytes(data, size);
  try {
    if (kFormat == "auto") check(voxd::decode_mesh(bytes, "", limits));
    else check(voxd::decode_mesh_as(format_of(kFormat), bytes, limits));
  } catch (const voxd::Error&) {
  }
  return 0;
}
