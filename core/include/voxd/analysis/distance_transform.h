#pragma once
// Exact Euclidean distance transform of a binary volume (Meijster, Roerdink &
// Hesselink 2000; the same lower envelope of parabolas as Felzenszwalb &
// Huttenlocher 2012), separable over x, then y, then z.
//
// For every filled voxel: the squared distance, in voxel units, from its
// centre to the nearest EMPTY voxel centre; 0 for empty voxels. Everything
// outside the grid counts as empty, so a filled voxel on the grid border has
// distance 1 and the result does not depend on how much padding a grid has
// beyond one empty layer. The values are integers (sums of three squares),
// computed in integer arithmetic: no rounding anywhere.
//
// Memory: one uint32 per voxel (the result) plus one small line buffer per
// thread. uint32 is enough: a voxel is never farther from the outside than
// half the smallest grid dimension, so d^2 <= ((kMaxGridDim + 1) / 2)^2 < 2^31.
#include <cstdint>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd {

// `threads` 0 = all cores. `control` may be null; when given, progress goes
// from 0 to 1 and cancellation (Error(cancelled)) is honoured between lines.
DenseVolume<std::uint32_t> squared_distance_transform(const BitVolume& solid, int threads = 0,
                                                      JobControl* control = nullptr);

}  // namespace voxd
