// VTK's vtkPolyDataToImageStencil (solid voxelization by slicing) against
// voxd's parity voxelizer, on the same mesh and the same grid, in one run.
// Prints wall time of each and their filled-voxel counts.
//   vtk_stencil_bench RESOLUTION [RESOLUTION...]
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <vtkCellArray.h>
#include <vtkImageStencilData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataToImageStencil.h>
#include <vtkSmartPointer.h>

#include "../bench_mesh.h"
#include "voxd/grid.h"
#include "voxd/voxelize/voxelize.h"

using namespace voxd;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const Mesh mesh = bench::make_benchmark_mesh();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.vertices.size()));
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    points->SetPoint(static_cast<vtkIdType>(i), mesh.vertices[i].x, mesh.vertices[i].y, mesh.vertices[i].z);
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& t : mesh.triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    polys->InsertNextCell(3, ids);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetPolys(polys);

  std::printf("%-6s %12s %12s %14s %14s\n", "res", "vtk_s", "voxd_s", "vtk_filled", "voxd_filled");
  for (int a = 1; a < argc; ++a) {
    GridRequest req;
    req.resolution = std::atoi(argv[a]);
    req.padding = 1;
    const Grid g = resolve_grid(req, bounds(mesh));

    auto t0 = std::chrono::steady_clock::now();
    auto stencil = vtkSmartPointer<vtkPolyDataToImageStencil>::New();
    stencil->SetInputData(poly);
    stencil->SetOutputOrigin(g.origin.x + 0.5 * g.voxel_size, g.origin.y + 0.5 * g.voxel_size,
                             g.origin.z + 0.5 * g.voxel_size);  // VTK's origin is the first voxel centre
    stencil->SetOutputSpacing(g.voxel_size, g.voxel_size, g.voxel_size);
    stencil->SetOutputWholeExtent(0, static_cast<int>(g.dims.x) - 1, 0, static_cast<int>(g.dims.y) - 1, 0,
                                  static_cast<int>(g.dims.z) - 1);
    stencil->Update();
    const double vtk_s = seconds_since(t0);
    vtkImageStencilData* data = stencil->GetOutput();
    std::uint64_t vtk_filled = 0;
    for (int z = 0; z < g.dims.z; ++z)
      for (int y = 0; y < g.dims.y; ++y) {
        int iter = 0, r1 = 0, r2 = 0;
        while (data->GetNextExtent(r1, r2, 0, static_cast<int>(g.dims.x) - 1, y, z, iter))
          vtk_filled += static_cast<std::uint64_t>(r2 - r1 + 1);
      }

    t0 = std::chrono::steady_clock::now();
    const BitVolume v = voxelize_parity(mesh, g, 0, 0, nullptr);
    const double voxd_s = seconds_since(t0);
    std::printf("%-6lld %12.3f %12.3f %14llu %14llu\n", static_cast<long long>(req.resolution), vtk_s, voxd_s,
                static_cast<unsigned long long>(vtk_filled), static_cast<unsigned long long>(v.count()));
  }
  return 0;
}
