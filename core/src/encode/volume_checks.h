#pragma once
// Checks shared by the encoders (is there a volume to write?) and decoders
// (may we allocate what a valid input describes?).
#include <cstdint>
#include <string>

#include "voxd/dense_volume.h"
#include "voxd/error.h"
#include "voxd/grid.h"
#include "voxd/encode/volume_format.h"

namespace voxd::encode {

// A default-constructed volume has dims 0 and no storage.
inline void require_voxels(const Grid& grid, const char* writer) {
  if (grid.dims.x < 1 || grid.dims.y < 1 || grid.dims.z < 1)
    throw Error(ErrorCode::invalid_argument, std::string(writer) + ": the volume has no voxels");
}

// values() is a public vector a caller could resize; encoders index it by
// the grid, so the two must agree.
template <typename T>
void require_voxels(const DenseVolume<T>& volume, const char* writer) {
  require_voxels(volume.grid(), writer);
  if (volume.values().size() != volume.grid().voxel_count())
    throw Error(ErrorCode::invalid_argument, std::string(writer) + ": the volume holds " +
                                                 std::to_string(volume.values().size()) + " values for " +
                                                 std::to_string(volume.grid().voxel_count()) + " voxels");
}

using voxd::bit_volume_bytes;

inline void check_read_limit(std::uint64_t volume_bytes, const ReadLimits& limits, const char* reader) {
  if (volume_bytes > limits.max_volume_bytes)
    throw Error(ErrorCode::limit_exceeded, std::string(reader) + ": the decoded volume would need " +
                                               std::to_string(volume_bytes) + " bytes, over the limit of " +
                                               std::to_string(limits.max_volume_bytes));
}

}  // namespace voxd::encode
