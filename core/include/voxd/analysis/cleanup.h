#pragma once
// Removal of voxel debris before analysis (Patil & Ravi): isolated voxels and
// structures one voxel thin (lines, sheets) come from sampling, not from the
// part, and would show up as spurious thin walls and tiny parts.
#include <cstdint>

#include "voxd/bit_volume.h"

namespace voxd {

struct CleanupOptions {
  bool isolated = true;  // no face neighbour at all
  bool lines = true;     // both face neighbours empty along two axes
  bool sheets = false;   // both face neighbours empty along one axis (a one-voxel wall)
};

struct CleanupReport {
  std::uint64_t isolated = 0, lines = 0, sheets = 0;
  std::uint64_t removed() const { return isolated + lines + sheets; }
};

// One simultaneous pass: every voxel is judged on the input, so removing one
// does not make its neighbour removable in the same call. Voxels outside the
// grid count as empty. Word-parallel (64 voxels at a time), multithreaded.
CleanupReport clean_up(BitVolume& volume, const CleanupOptions& options, int threads = 0);

}  // namespace voxd
