// /metrics labels requests by documented path template only, so no client
// can grow the label set with invented paths, ids or layer numbers.
#include <gtest/gtest.h>

#include "server/http/route_label.h"

namespace voxd::server {
namespace {

TEST(RouteLabel, IsADocumentedPathTemplateOrOther) {
  const std::string id(32, 'a');
  EXPECT_EQ(route_label("/v1/jobs"), "/v1/jobs");
  EXPECT_EQ(route_label("/v1/jobs/" + id), "/v1/jobs/{id}");
  EXPECT_EQ(route_label("/v1/jobs/" + id + "/layers/999999"), "/v1/jobs/{id}/layers/{k}");
  EXPECT_EQ(route_label("/v1/jobs/" + id + "/layers/1"), "/v1/jobs/{id}/layers/{k}");
  EXPECT_EQ(route_label("/v1/jobs/" + id + "/volume"), "/v1/jobs/{id}/volume");
  EXPECT_EQ(route_label("/v1/jobs/" + id + "/invented-" + id), "other");
  EXPECT_EQ(route_label("/v1/jobs/" + id + "/layers/1/more"), "other");
  EXPECT_EQ(route_label("/v1/jobs/"), "other");
  EXPECT_EQ(route_label("/"), "/");
  EXPECT_EQ(route_label("/docs"), "/docs");
  EXPECT_EQ(route_label("/ui/vendor/three.module.js"), "/ui/{file}");
  EXPECT_EQ(route_label("/ui/"), "other");
  EXPECT_EQ(route_label("/wp-admin/" + id), "other");
}

}  // namespace
}  // namespace voxd::server
