#pragma once
// A job's volumes, one type from the mode that makes them (JobMode::run)
// through the pipeline's result (VoxelJobResult) to the store and the cache
// (server::JobOutput), so none of them copies the data into a type of its
// own. Shared and immutable once made: a finished job's volumes are read by
// its encoders, its analyses and the cache at once.
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/encode/volume_format.h"  // ValueVolume

namespace voxd::api {

struct JobVolumes {
  // The job's bits: the result of a job of bits, the solid (centre inside)
  // of a value job, which the analyses measure. Null when the mode makes no
  // bits of its own (they are then the parity solid made before it ran) and
  // for a job made slab by slab, whose bits went to their consumer.
  std::shared_ptr<const BitVolume> solid;
  // The job's result when it is a volume of values.
  std::shared_ptr<const ValueVolume> values;
  // Further volumes kept beside the values, by name (JobMode::stored_layers()).
  std::vector<std::pair<std::string, std::shared_ptr<const ValueVolume>>> layers;
  // What the values are, for the job status and the CLI summary
  // (proto-schemas/job-status.schema.json "values"): {"type", "quantity",
  // "unit", ...}; null for a job of bits.
  nlohmann::json values_info;

  // "values" (the result) or a kept layer by name; null for one the job
  // does not have (a VolumeSource, api/job_mode.h).
  std::shared_ptr<const ValueVolume> volume(std::string_view name) const {
    if (name == "values") return values;
    for (const auto& [layer, v] : layers)
      if (layer == name) return v;
    return nullptr;
  }
};

}  // namespace voxd::api
