#pragma once
// Binary voxelization straight to runs: each x-row's filled runs come from its
// sorted ray crossings (the parity solid) and its surface voxels, chunk by
// chunk of z layers, without a dense bit volume being filled and scanned
// again. The voxels are exactly voxelize()'s and voxelize_streamed()'s; an
// output made of runs (voxd's RLE) is then written for the cost of its runs,
// and memory is the mesh, its bins and a few chunks' runs whatever the grid.
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/run_slab.h"
#include "voxd/voxelize/streamed.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {

// Whether these options make runs: those that stream (can_stream: the
// parity inside test, in every mode).
bool can_make_runs(const VoxelizeOptions& options);

// Hands z layers [range.begin, range.end) to `consume` as slabs of runs of a
// few layers each, in z order. With `prepare`, each slab goes through it
// first, on the thread that made it (in parallel, in any order): the
// consumer's own work that need not wait its turn (a writer's encoding). Throws
// Error(invalid_argument) for options that do not make runs or a range off the
// grid. Progress runs over the layers; cancellation is honoured between slabs.
void voxelize_runs(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, const RunSlabConsumer& consume,
                   JobControl* control = nullptr, LayerRange range = {}, const RunSlabPreparer& prepare = {});

}  // namespace voxd
