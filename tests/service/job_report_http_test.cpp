// GET /v1/jobs/{id}/report through the real `voxd serve`: one HTML file with
// the verdict the analysis route gives, the job's own limits unless the
// query gives others, the pictures inline, nothing fetched or run, the
// uploaded name escaped in the page and made safe in the file name.
#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "support/test_meshes.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using JobReportTest = HttpServiceTest;

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST_F(JobReportTest, TheReportHoldsTheVerdictInputsAndPicturesAndNeedsNothingElse) {
  start();
  // Walls 2 thick against a min wall of 3: certainly thin.
  const Mesh box = concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10}))});
  const std::string id = finished(submit(to_binary_stl(box),
                                         R"({"grid":{"resolution":40},"analyses":[{"kind":"analysis","min_wall":3}]})",
                                         "<b>\"odd\" part.stl"));
  auto res = http().Get(("/v1/jobs/" + id + "/report").c_str());
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_EQ(res->get_header_value("Content-Disposition"), "attachment; filename=\"_b__odd__part-report.html\"");
  const std::string& html = res->body;
  EXPECT_NE(html.find("<span class=\"verdict fail\">fail</span>"), std::string::npos);
  EXPECT_NE(html.find("<h1>&lt;b&gt;&quot;odd&quot; part.stl</h1>"), std::string::npos);
  EXPECT_EQ(html.find("<b>\"odd\""), std::string::npos);
  EXPECT_EQ(occurrences(html, "src=\"data:image/png;base64,iVBORw0KGgo"), 3u);  // PNG signature, base64
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  // The same verdict and reason as the analysis route's.
  const json report = json::parse(http().Get(("/v1/jobs/" + id + "/analysis?min_wall=3").c_str())->body);
  EXPECT_EQ(report.at("thickness").at("verdict"), "fail");
  EXPECT_NE(html.find("min wall 3,"), std::string::npos);
  // The query's limits over the job's: a min wall of 1 passes.
  const std::string relaxed = http().Get(("/v1/jobs/" + id + "/report?min_wall=1").c_str())->body;
  EXPECT_NE(relaxed.find("<span class=\"verdict pass\">pass</span>"), std::string::npos);
}

TEST_F(JobReportTest, AWrongQueryIsA400AndAnUnknownJobA404) {
  start();
  const std::string id = finished(submit(to_binary_stl(make_box({0, 0, 0}, {4, 4, 4})), R"({"grid":{"resolution":8}})"));
  const json p = expect_problem(http().Get(("/v1/jobs/" + id + "/report?min_wall=thin").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("min_wall"), std::string::npos) << p;
  expect_problem(http().Get(("/v1/jobs/" + id + "/report?colour=red").c_str()), 400, "invalid-query");
  expect_problem(http().Get("/v1/jobs/0123456789abcdef0123456789abcdef/report"), 404, "not-found");
}

}  // namespace
}  // namespace voxd::test
