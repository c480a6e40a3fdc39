// OpenVDB's mesh-to-level-set conversion (tools::meshToVolume, through
// tools::meshToSignedDistanceField, its points-and-triangles entry point,
// which calls meshToVolume with the default flags) against voxd's exact
// narrow-band signed distance field: the benchmark mesh (1.1M triangles),
// the same grid, a band of 3 voxels on both sides, in one run.
//   openvdb_sdf_bench [RESOLUTION...]   (default 256 512)
//
// Per resolution it prints the wall time of each (best of 2, all cores for
// both; the first runs too, which map fresh memory: a second voxd run reuses
// the first's volume memory, voxd/volume_memory.h, as a service's next job
// of the same grid does), OpenVDB's error against voxd's values on the voxels both have in
// their band (overall and by depth), the voxels whose signs differ (refereed
// by the side of the nearest face), and how many voxels each band holds;
// then the process's peak RSS. voxd's values are first checked against a
// brute force (point_triangle_distance2 over the triangles near the voxel) on
// a random sample of band voxels, so they can serve as the exact reference.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include "../bench_mesh.h"
#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/voxelize/sdf.h"

using namespace voxd;

namespace {

constexpr double kBand = 3.0;  // voxels, both sides, for both libraries

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double millions(std::uint64_t n) { return static_cast<double>(n) / 1e6; }

// Triangles binned on a uniform grid of cubic cells: a cell lists every
// triangle whose bounding box, grown by `reach`, overlaps it. So every
// triangle whose box is within `reach` of a point is in the point's cell.
class TriangleBins {
 public:
  TriangleBins(const Mesh& mesh, const Grid& grid, double reach, double cell)
      : mesh_(mesh), origin_(grid.origin), cell_(cell), reach_(reach) {
    const glm::dvec3 size = glm::dvec3(grid.dims) * grid.voxel_size;
    for (int a = 0; a < 3; ++a) n_[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(size[a] / cell)));
    const std::size_t cells = static_cast<std::size_t>(n_[0] * n_[1] * n_[2]);
    start_.assign(cells + 1, 0);
    // Two passes: count, then fill (compressed rows).
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> fill;
      if (pass == 1) {
        for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
        items_.resize(start_[cells]);
        fill.assign(start_.begin(), start_.end() - 1);
      }
      for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        glm::dvec3 lo, hi;
        box(t, lo, hi);
        std::int64_t c0[3], c1[3];
        for (int a = 0; a < 3; ++a) {
          c0[a] = cell_index(lo[a] - reach - origin_[a], a);
          c1[a] = cell_index(hi[a] + reach - origin_[a], a);
        }
        for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
          for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
            for (std::int64_t x = c0[0]; x <= c1[0]; ++x) {
              const auto c = static_cast<std::size_t>(x + n_[0] * (y + n_[1] * z));
              if (pass == 0)
                ++start_[c + 1];
              else
                items_[fill[c]++] = t;
            }
      }
    }
  }

  // Smallest point_triangle_distance2 from p over the triangles whose
  // bounding box is within `reach` of p; infinity when there is none.
  double nearest_distance2(const glm::dvec3& p, std::size_t* candidates, std::uint32_t* nearest = nullptr) const {
    std::int64_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = cell_index(p[a] - origin_[a], a);
    const auto cell = static_cast<std::size_t>(c[0] + n_[0] * (c[1] + n_[1] * c[2]));
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t n = start_[cell]; n < start_[cell + 1]; ++n) {
      const std::uint32_t t = items_[n];
      glm::dvec3 lo, hi;
      box(t, lo, hi);
      double box2 = 0.0;
      for (int a = 0; a < 3; ++a) {
        const double d = std::max({lo[a] - p[a], p[a] - hi[a], 0.0});
        box2 += d * d;
      }
      if (box2 > reach_ * reach_) continue;
      ++*candidates;
      const double d2 = point_triangle_distance2(p, glm::dvec3(mesh_.corner(t, 0)), glm::dvec3(mesh_.corner(t, 1)),
                                                 glm::dvec3(mesh_.corner(t, 2)));
      if (d2 < best) {
        best = d2;
        if (nearest) *nearest = t;
      }
    }
    return best;
  }

 private:
  void box(std::uint32_t t, glm::dvec3& lo, glm::dvec3& hi) const {
    const glm::dvec3 a(mesh_.corner(t, 0)), b(mesh_.corner(t, 1)), c(mesh_.corner(t, 2));
    lo = glm::min(a, glm::min(b, c));
    hi = glm::max(a, glm::max(b, c));
  }
  std::int64_t cell_index(double offset, int axis) const {
    const double c = std::floor(offset / cell_);
    if (!(c > 0.0)) return 0;
    return std::min(n_[axis] - 1, static_cast<std::int64_t>(c));
  }

  const Mesh& mesh_;
  glm::dvec3 origin_;
  double cell_, reach_;
  std::int64_t n_[3];
  std::vector<std::size_t> start_;
  std::vector<std::uint32_t> items_;
};

// Accumulated error in voxels: e = OpenVDB's value - the exact one; `over`
// = OpenVDB's |d| - the exact |d| (positive: farther than the surface is).
struct ErrorStats {
  std::uint64_t count = 0;
  double sum2 = 0.0, max = 0.0, max_over = 0.0, max_under = 0.0;
  void add(double e, double over) {
    ++count;
    sum2 += e * e;
    max = std::max(max, std::abs(e));
    max_over = std::max(max_over, over);
    max_under = std::max(max_under, -over);
  }
  double rms() const { return count ? std::sqrt(sum2 / static_cast<double>(count)) : 0.0; }
};

// Which side of triangle t's plane p is on, when p's nearest point on t (at
// squared distance d2) is inside the face, where that plane decides the side
// of a closed surface: +1 where the normal (b - a) x (c - a) points, -1 on
// the other side; 0 when the nearest point is on an edge or a vertex, or p is
// on the plane.
int face_side(const Mesh& m, std::uint32_t t, const glm::dvec3& p, double d2) {
  const glm::dvec3 a(m.corner(t, 0)), b(m.corner(t, 1)), c(m.corner(t, 2));
  const glm::dvec3 n = glm::cross(b - a, c - a);
  const double nn = glm::dot(n, n), s = glm::dot(p - a, n);
  if (s == 0.0 || !(nn > 0.0) || s * s / nn < d2 * (1.0 - 1e-9)) return 0;
  return s > 0.0 ? 1 : -1;
}

}  // namespace

// Wall time of one whole `voxd voxelize` run (a fresh process: map the STL,
// parse, the solid for the sign, the band, write the output).
double voxd_cli_seconds(const std::string& voxd, const std::string& stl, std::int64_t n, const std::string& out) {
  const std::string command = voxd + " voxelize " + stl + " --resolution " + std::to_string(n) +
                              " --padding 3 --mode sdf -o " + out + " > /dev/null 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  if (std::system(command.c_str()) != 0) {
    std::fprintf(stderr, "failed: %s\n", command.c_str());
    std::exit(1);
  }
  return seconds_since(t0);
}

int main(int argc, char** argv) {
  std::vector<std::int64_t> resolutions;
  std::string voxd_cli;  // --cli PATH: also time whole voxd voxelize runs
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--cli" && a + 1 < argc) {
      voxd_cli = argv[++a];
      continue;
    }
    resolutions.push_back(std::atoll(argv[a]));
  }
  if (resolutions.empty()) resolutions = {256, 512};

  openvdb::initialize();
  const Mesh& mesh = bench::benchmark_mesh();
  const std::string stl = "/tmp/openvdb_sdf_bench_mesh.stl";
  if (!voxd_cli.empty()) test::write_file(stl, test::to_binary_stl(mesh));

  // OpenVDB's input, in its own types (built once, outside the timings).
  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) points.emplace_back(v.x, v.y, v.z);
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  const std::vector<openvdb::Vec4I> quads;
  std::printf("mesh: %zu triangles, %zu vertices; OpenVDB %s, band %.0f voxels each side\n", mesh.triangles.size(),
              mesh.vertices.size(), openvdb::getLibraryAbiVersionString(), kBand);

  for (const std::int64_t n : resolutions) {
    const Grid g = bench::benchmark_grid(n, 3);
    const double h = g.voxel_size;
    std::printf("N=%lld grid %lld x %lld x %lld, voxel %.6g\n", static_cast<long long>(n),
                static_cast<long long>(g.dims.x), static_cast<long long>(g.dims.y), static_cast<long long>(g.dims.z), h);

    // voxd.
    SdfOptions o;
    o.band = kBand;
    o.model_units = true;
    o.sign = SignConvention::inside_negative;
    DenseVolume<float> sdf;
    double voxd_s = std::numeric_limits<double>::infinity(), voxd_first = 0.0;
    for (int run = 0; run < 2; ++run) {
      sdf = DenseVolume<float>();
      const auto t0 = std::chrono::steady_clock::now();
      sdf = signed_distance_field(mesh, g, o);
      const double t = seconds_since(t0);
      if (run == 0) voxd_first = t;
      voxd_s = std::min(voxd_s, t);
    }

    // OpenVDB: voxel (i,j,k) centred where voxd's voxel (i,j,k) is. OpenVDB's
    // integer index coordinates are voxel centres; voxd's centres sit at
    // origin + (i + 1/2) h.
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(h);
    xform->postTranslate(openvdb::Vec3d(g.origin.x + 0.5 * h, g.origin.y + 0.5 * h, g.origin.z + 0.5 * h));
    double centre_offset = 0.0;
    for (const openvdb::Coord c : {openvdb::Coord(0, 0, 0), openvdb::Coord(static_cast<int>(g.dims.x - 1),
                                                                            static_cast<int>(g.dims.y - 1),
                                                                            static_cast<int>(g.dims.z - 1))}) {
      const openvdb::Vec3d w = xform->indexToWorld(c);
      const glm::dvec3 v = g.center(c.x(), c.y(), c.z());
      centre_offset = std::max({centre_offset, std::abs(w.x() - v.x), std::abs(w.y() - v.y), std::abs(w.z() - v.z)});
    }
    openvdb::FloatGrid::Ptr vdb;
    double vdb_s = std::numeric_limits<double>::infinity(), vdb_first = 0.0;
    for (int run = 0; run < 2; ++run) {
      vdb.reset();
      const auto t0 = std::chrono::steady_clock::now();
      vdb = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(*xform, points, triangles, quads,
                                                                           static_cast<float>(kBand),
                                                                           static_cast<float>(kBand));
      const double t = seconds_since(t0);
      if (run == 0) vdb_first = t;
      vdb_s = std::min(vdb_s, t);
    }

    // voxd's band and its exactness on a random sample.
    const float band_limit = static_cast<float>(kBand * h);
    std::uint64_t voxd_band = 0;
    for (const float v : sdf.values())
      if (std::abs(v) < band_limit) ++voxd_band;
    std::uint64_t sampled = 0, identical = 0, no_candidate = 0;
    std::size_t candidates = 0;
    double exact_max_diff = 0.0;
    // Also which way the triangles' normals point: on sampled voxels off the
    // surface (|d| > h/2) whose nearest point is inside a face, does the
    // face's normal side agree with voxd's sign (outside = positive)?
    std::uint64_t normal_checked = 0, normal_outward = 0;
    const TriangleBins bins(mesh, g, kBand * h, 8.0 * h);
    {
      std::mt19937_64 rng(12345);
      std::uniform_int_distribution<std::int64_t> pick_i(0, g.dims.x - 1), pick_j(0, g.dims.y - 1),
          pick_k(0, g.dims.z - 1);
      while (sampled < 10000 && voxd_band > 0) {
        const std::int64_t i = pick_i(rng), j = pick_j(rng), k = pick_k(rng);
        const float v = sdf.at(i, j, k);
        if (!(std::abs(v) < band_limit)) continue;
        ++sampled;
        std::uint32_t t = 0;
        const double d2 = bins.nearest_distance2(g.center(i, j, k), &candidates, &t);
        if (!std::isfinite(d2)) {
          ++no_candidate;
          continue;
        }
        const auto brute = static_cast<float>(std::sqrt(d2));
        if (brute == std::abs(v)) ++identical;
        exact_max_diff = std::max(exact_max_diff, std::abs(static_cast<double>(brute) - std::abs(v)) / h);
        const int side = face_side(mesh, t, g.center(i, j, k), d2);
        if (side != 0 && std::abs(v) > 0.5 * h) {
          ++normal_checked;
          if ((side > 0) == (v > 0.0f)) ++normal_outward;
        }
      }
    }
    const int outward = 2 * normal_outward >= normal_checked ? 1 : -1;

    // OpenVDB against voxd, on the voxels in both bands.
    ErrorStats all, by_depth[3];
    std::uint64_t common = 0, vdb_only = 0, vdb_outside = 0, vdb_tiles = 0, sign_diff = 0;
    double sign_diff_max_depth = 0.0;  // largest exact |d| (voxels) among the sign differences
    // Sign differences refereed by the nearest face's side (see face_side).
    std::uint64_t side_voxd = 0, side_vdb = 0, side_undecided = 0, voxd_zero = 0;
    float vdb_min = 0.0f, vdb_max = 0.0f;
    for (auto it = vdb->cbeginValueOn(); it; ++it) {
      if (!it.isVoxelValue()) {
        ++vdb_tiles;
        continue;
      }
      const openvdb::Coord c = it.getCoord();
      const float dv = *it;
      vdb_min = std::min(vdb_min, dv);
      vdb_max = std::max(vdb_max, dv);
      if (c.x() < 0 || c.y() < 0 || c.z() < 0 || c.x() >= g.dims.x || c.y() >= g.dims.y || c.z() >= g.dims.z) {
        ++vdb_outside;
        continue;
      }
      const float dx = sdf.at(c.x(), c.y(), c.z());
      if (!(std::abs(dx) < band_limit)) {
        ++vdb_only;
        continue;
      }
      ++common;
      const double e = (static_cast<double>(dv) - static_cast<double>(dx)) / h;
      const double over = (std::abs(static_cast<double>(dv)) - std::abs(static_cast<double>(dx))) / h;
      all.add(e, over);
      const double depth = std::abs(static_cast<double>(dx)) / h;
      by_depth[std::min(2, static_cast<int>(depth))].add(e, over);
      if ((dv < 0.0f) != (dx < 0.0f)) {
        ++sign_diff;
        sign_diff_max_depth = std::max(sign_diff_max_depth, depth);
        if (dx == 0.0f) {
          ++voxd_zero;  // a centre on the surface: voxd gives +0 by definition
          continue;
        }
        std::size_t unused = 0;
        std::uint32_t t = 0;
        const glm::dvec3 p = g.center(c.x(), c.y(), c.z());
        const double d2 = bins.nearest_distance2(p, &unused, &t);
        const int side = std::isfinite(d2) ? face_side(mesh, t, p, d2) * outward : 0;
        if (side == 0)
          ++side_undecided;
        else if ((side > 0) == (dx > 0.0f))
          ++side_voxd;
        else
          ++side_vdb;
      }
    }
    const std::uint64_t vdb_band = vdb->activeVoxelCount();

    std::printf(
        "N=%lld voxd %.2f s  openvdb %.2f s  ratio %.2f  openvdb max error %.3f voxel rms %.3f voxel  sign differences "
        "%llu  band voxels voxd %.2fM openvdb %.2fM\n",
        static_cast<long long>(n), voxd_s, vdb_s, voxd_s / vdb_s, all.max, all.rms(),
        static_cast<unsigned long long>(sign_diff), millions(voxd_band), millions(vdb_band));
    std::printf("  first runs: voxd %.2f s  openvdb %.2f s  ratio %.2f\n", voxd_first, vdb_first, voxd_first / vdb_first);
    if (!voxd_cli.empty()) {
      // The whole command against OpenVDB's meshToVolume alone, right after
      // it, best of 2 each: to the sparse f32 RLE (the clamped background as
      // runs) and to the dense f32 NRRD.
      for (const char* out : {"/tmp/openvdb_sdf_bench_out.rle", "/tmp/openvdb_sdf_bench_out.nrrd"}) {
        const double t = std::min(voxd_cli_seconds(voxd_cli, stl, n, out), voxd_cli_seconds(voxd_cli, stl, n, out));
        std::printf("  whole voxd voxelize to %s: %.2f s, %.2f of openvdb's meshToVolume\n", std::strrchr(out, '.') + 1, t,
                    t / vdb_s);
        std::remove(out);
      }
    }
    std::printf("  grid alignment: largest centre offset %.3g (model units)\n", centre_offset);
    std::printf("  voxd exactness: %llu band voxels sampled, %llu equal to the brute force bit for bit, max diff %.3g voxel"
                " (%.0f candidate triangles a voxel, %llu with none)\n",
                static_cast<unsigned long long>(sampled), static_cast<unsigned long long>(identical), exact_max_diff,
                sampled ? static_cast<double>(candidates) / static_cast<double>(sampled) : 0.0,
                static_cast<unsigned long long>(no_candidate));
    std::printf("  coverage: in both bands %.3fM, voxd only %.3fM, openvdb only %.3fM (+%llu outside the grid, %llu tiles);"
                " openvdb values in [%.3f, %.3f] voxel\n",
                millions(common), millions(voxd_band - common), millions(vdb_only),
                static_cast<unsigned long long>(vdb_outside), static_cast<unsigned long long>(vdb_tiles),
                static_cast<double>(vdb_min) / h, static_cast<double>(vdb_max) / h);
    std::printf("  openvdb error by exact depth (voxels; over/under: its |d| above/below the exact):\n");
    for (int d = 0; d < 3; ++d)
      std::printf("    [%d,%d) %.3fM voxels  max %.3f  rms %.4f  over up to %.3f  under up to %.3f\n", d, d + 1,
                  millions(by_depth[d].count), by_depth[d].max, by_depth[d].rms(), by_depth[d].max_over,
                  by_depth[d].max_under);
    std::printf("  sign differences %llu, at exact depth up to %.4f voxel: voxd +0 on the surface %llu; nearest face's"
                " side agrees with voxd %llu, with openvdb %llu, undecided (edge or vertex nearest) %llu"
                " [normals outward on %llu of %llu sampled voxels]\n",
                static_cast<unsigned long long>(sign_diff), sign_diff_max_depth,
                static_cast<unsigned long long>(voxd_zero), static_cast<unsigned long long>(side_voxd),
                static_cast<unsigned long long>(side_vdb), static_cast<unsigned long long>(side_undecided),
                static_cast<unsigned long long>(normal_outward), static_cast<unsigned long long>(normal_checked));
    std::fflush(stdout);
  }

  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::printf("peak RSS %.0f MiB\n", static_cast<double>(ru.ru_maxrss) / 1024.0);
  return 0;
}
