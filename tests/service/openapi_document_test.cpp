// The document served at /openapi.json is self-contained (every $ref a JSON
// pointer into itself, as third-party tools need), holds the repository's
// schemas unchanged but for where their $refs point.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "server/http/openapi_document.h"

namespace voxd::server {
namespace {

using nlohmann::json;

json repo_file(const std::string& name) {
  std::ifstream in(std::string(VOXD_SOURCE_DIR) + "/proto-schemas/" + name);
  std::stringstream text;
  text << in.rdbuf();
  return json::parse(text.str());
}

void collect_refs(const json& node, std::vector<std::string>& out) {
  if (node.is_object()) {
    for (const auto& [key, value] : node.items()) {
      if (key == "$ref" && value.is_string()) out.push_back(value);
      else collect_refs(value, out);
    }
  } else if (node.is_array()) {
    for (const auto& v : node) collect_refs(v, out);
  }
}

// JSON pointer "/a/b~1c" -> json_pointer; refs escape '/' in names as ~1.
TEST(OpenApiDocument, EveryRefOfTheServedDocumentPointsIntoItself) {
  const json served = json::parse(served_openapi_document());
  std::vector<std::string> refs;
  collect_refs(served, refs);
  ASSERT_GT(refs.size(), 100u);
  std::size_t into_job_params = 0, into_analysis = 0;
  for (const std::string& ref : refs) {
    ASSERT_EQ(ref.rfind("#/", 0), 0u) << ref << " is not a pointer into the document";
    EXPECT_TRUE(served.contains(json::json_pointer(ref.substr(1)))) << ref << " does not resolve";
    into_job_params += ref.rfind("#/components/schemas/JobParams/", 0) == 0;
    into_analysis += ref.rfind("#/components/schemas/Analysis/", 0) == 0;
  }
  // The schemas' own "#/$defs/..." were moved with them.
  EXPECT_GT(into_job_params, 10u);
  EXPECT_GT(into_analysis, 3u);
  EXPECT_EQ(served.dump().find(".schema.json\""), std::string::npos);
}

// What moved in is the repository's schema: same keys and texts, no $id.
TEST(OpenApiDocument, TheEmbeddedSchemasAreTheRepositorysAndTheRestIsUnchanged) {
  json served = json::parse(served_openapi_document());
  const json job_params = repo_file("job-params.schema.json");
  const json analysis = repo_file("analysis.schema.json");
  auto& schemas = served["components"]["schemas"];
  EXPECT_FALSE(schemas["JobParams"].contains("$id"));
  EXPECT_EQ(schemas["JobParams"]["title"], job_params["title"]);
  EXPECT_EQ(schemas["JobParams"]["$defs"].size(), job_params["$defs"].size());
  EXPECT_EQ(schemas["JobParams"]["properties"]["grid"]["oneOf"][0]["properties"]["padding"]["$ref"],
            "#/components/schemas/JobParams/$defs/padding");
  EXPECT_EQ(schemas["Analysis"]["required"], analysis["required"]);
  schemas["JobParams"] = {{"$ref", "job-params.schema.json"}};
  schemas["Analysis"] = {{"$ref", "analysis.schema.json"}};
  EXPECT_EQ(served, repo_file("openapi.json"));
}

TEST(OpenApiDocument, ARefToAFileNotEmbeddedIsRefusedRatherThanServedBroken) {
  const json doc = {{"openapi", "3.1.0"},
                    {"paths", json::object()},
                    {"components", {{"schemas", {{"A", {{"$ref", "a.schema.json"}}}, {"B", {{"$ref", "b.schema.json"}}}}}}}};
  const json a = {{"$id", "x"}, {"type", "object"}, {"properties", {{"n", {{"$ref", "#/$defs/n"}}}}}, {"$defs", {{"n", {{"type", "integer"}}}}}};
  EXPECT_THROW(bundle_openapi(doc, {{"a.schema.json", a}}), std::runtime_error);  // b.schema.json missing
  const json b = {{"items", {{"$ref", "a.schema.json#/$defs/n"}}}};
  const json bundled = bundle_openapi(doc, {{"a.schema.json", a}, {"b.schema.json", b}});
  EXPECT_EQ(bundled["components"]["schemas"]["A"]["properties"]["n"]["$ref"], "#/components/schemas/A/$defs/n");
  EXPECT_EQ(bundled["components"]["schemas"]["B"]["items"]["$ref"], "#/components/schemas/A/$defs/n");
  EXPECT_THROW(bundle_openapi(doc, {{"a.schema.json", a}, {"b.schema.json", b}, {"c.schema.json", b}}), std::runtime_error);
}

}  // namespace
}  // namespace voxd::server
