// The thickness volume: the wall or local thickness of every voxel of the
// solid, in model units or voxels, as NRRD, raw floats or RLE.
#include "server/jobs/analyses/analysis_support.h"

#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {
namespace {

// The thickness map in the unit asked for: voxels as computed, or model
// units (times the voxel size).
DenseVolume<float> thickness_in(DenseVolume<float> map, const std::string& unit) {
  if (unit == "model") {
    const auto h = static_cast<float>(map.grid().voxel_size);
    for (float& v : map.values()) v *= h;
  }
  return map;
}

class ThicknessAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::thickness; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const api::AnalysisRequest& r = in.request;
    const DenseVolume<float> map =
        thickness_in(*job_thickness_map(volume, in.artifacts, in.control, r.thickness_measure), r.unit);
    VectorSink out;
    if (r.format == "rle") {
      write_rle(map, out);
    } else if (r.format == "raw") {
      write_raw(map, out);
    } else {
      write_nrrd(map,
                 std::string(to_string(r.thickness_measure)) + " thickness (" +
                     (r.unit == "model" ? "model units" : "voxels") + ")",
                 out);
    }
    return to_bytes(out.data);
  }

  // The map's 18 bytes a voxel, then the map in the asked unit, the encoded
  // volume and its kept copy.
  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest&) const override { return 18 + 12; }

  std::string needs_whole_grid(const api::AnalysisRequest& r) const override {
    return std::string("the ") + to_string(r.thickness_measure) + " thickness volume";
  }
};

}  // namespace

const JobAnalysisKind& thickness_analysis() {
  static const ThicknessAnalysis kind;
  return kind;
}

}  // namespace voxd::server
