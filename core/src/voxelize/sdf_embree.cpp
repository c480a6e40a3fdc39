// Nearest triangle by Embree's rtcPointQuery; see sdf_embree.h.
#include "voxelize/sdf_embree.h"
#include "voxelize/sdf_fill.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "voxd/error.h"

namespace voxd::sdf {
namespace {

struct QueryState {
  const Mesh* mesh;
  dvec3 p;
  double slack;
  EmbreeNearest::Hit best;
};

// The float radius Embree culls with: at least sqrt(d2) + slack (the centre's
// float rounding and Embree's float box distances), rounded up.
float culling_radius(double d2, double slack) {
  if (!std::isfinite(d2)) return std::numeric_limits<float>::infinity();
  const double r = (std::sqrt(d2) + slack) * (1.0 + 1e-6);
  const auto f = static_cast<float>(r);
  return static_cast<double>(f) >= r ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}

bool visit(RTCPointQueryFunctionArguments* args) {
  auto* state = static_cast<QueryState*>(args->userPtr);
  const std::size_t t = args->primID;
  const double d2 = distance2(Triangle(dvec3(state->mesh->corner(t, 0)), dvec3(state->mesh->corner(t, 1)),
                                       dvec3(state->mesh->corner(t, 2))),
                              state->p);
  if (!(d2 < state->best.d2)) return false;
  state->best = {d2, static_cast<std::uint32_t>(t)};
  args->query->radius = culling_radius(d2, state->slack);
  return true;
}

}  // namespace

EmbreeNearest::EmbreeNearest(const Mesh& mesh) : mesh_(mesh) {
  if (mesh.triangle_count() == 0) return;
  if (mesh.triangle_count() >= kNone) throw Error(ErrorCode::limit_exceeded, "too many triangles for the distance field");
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw std::runtime_error("Embree device creation failed");
  device_ = device;
  RTCScene scene = rtcNewScene(device);
  scene_ = scene;
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Embree's own copies: it reads vertices as 16 bytes, past a shared vec3 array's end.
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.vertices.size()));
  auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), mesh.triangle_count()));
  std::memcpy(vertices, mesh.vertices.data(), mesh.vertices.size() * 3 * sizeof(float));
  std::memcpy(indices, mesh.triangles.data(), mesh.triangle_count() * 3 * sizeof(std::uint32_t));
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  // Coordinates are within `scale`; float rounding of the query point and of
  // Embree's box distances stays far below 16 ulps of it.
  double scale = 0.0;
  for (const glm::vec3& v : mesh.vertices)
    scale = std::max({scale, std::abs(static_cast<double>(v.x)), std::abs(static_cast<double>(v.y)),
                      std::abs(static_cast<double>(v.z))});
  slack_ = 16.0 * std::numeric_limits<float>::epsilon() * scale;
}

EmbreeNearest::~EmbreeNearest() {
  if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
  if (device_) rtcReleaseDevice(static_cast<RTCDevice>(device_));
}

EmbreeNearest::Hit EmbreeNearest::nearest(const dvec3& p, double bound2, std::uint32_t hint) const {
  QueryState state{&mesh_, p, slack_ + 16.0 * std::numeric_limits<float>::epsilon() *
                                          std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}),
                   {bound2, kNone}};
  if (!scene_) return state.best;
  if (hint != kNone) {
    const double d2 = distance2(
        Triangle(dvec3(mesh_.corner(hint, 0)), dvec3(mesh_.corner(hint, 1)), dvec3(mesh_.corner(hint, 2))), p);
    if (d2 < state.best.d2) state.best = {d2, hint};
  }
  RTCPointQuery query;
  query.x = static_cast<float>(p.x);
  query.y = static_cast<float>(p.y);
  query.z = static_cast<float>(p.z);
  query.time = 0.0f;
  query.radius = culling_radius(state.best.d2, state.slack);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(static_cast<RTCScene>(scene_), &query, &context, visit, &state);
  return state.best;
}

namespace {

void fill_by_embree(const Mesh& mesh, const Grid& g, const BandSetup& s, float clamped, int threads,
                    DenseVolume<float>& values, const detail::ProgressSpan& rest) {
  const EmbreeNearest nearest(mesh);
  rest.check_cancelled();
  fill_beyond_band(nearest, g, s, clamped, threads, values, rest.part(0.1, 1.0));
}

// Linked in as an object (CMake's voxd_sdf_embree), so this runs at start.
[[maybe_unused]] const bool registered = [] {
  embree_fill_beyond_band = fill_by_embree;
  return true;
}();

}  // namespace

}  // namespace voxd::sdf
