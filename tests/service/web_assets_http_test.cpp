// The web page's files as a browser gets them from a real `voxd serve`:
// each in the encoding it accepts (brotli, gzip, or as it is), decoded by
// httplib's client (libbrotlidec, zlib) to the bytes of the file in web/;
// with an ETag that a second request turns into a 304 without a body; and
// the icon browsers ask for.
#include "support/http_fixture.h"

namespace voxd::test {
namespace {

namespace fs = std::filesystem;

class WebAssetsTest : public HttpServiceTest {};

httplib::Result get(httplib::Client& c, const std::string& path, const std::string& accept, const std::string& etag = "") {
  httplib::Headers h = {{"Accept-Encoding", accept}};
  if (!etag.empty()) h.emplace("If-None-Match", etag);
  return c.Get(path.c_str(), h);
}

TEST_F(WebAssetsTest, EveryFileIsServedInTheEncodingAskedForWithAnETagThatAnswers304) {
  start();
  const fs::path web = fs::path(VOXD_SOURCE_DIR) / "web";
  std::vector<std::pair<std::string, fs::path>> files = {{"/", web / "index.html"},
                                                         {"/docs", web / "docs.html"},
                                                         {"/favicon.ico", web / "favicon.svg"},
                                                         {"/ui/vendor/three.core.js", web / "node_modules/three/build/three.core.js"}};
  for (const auto& entry : fs::directory_iterator(web / "js")) files.emplace_back("/ui/js/" + entry.path().filename().string(), entry.path());
  for (const char* f : {"style.css", "favicon.svg"}) files.emplace_back(std::string("/ui/") + f, web / f);
  for (const auto& [path, file] : files) {
    SCOPED_TRACE(path);
    const std::string want = text_of(read_file(file.string()));
    const auto plain = get(http(), path, "identity");
    ASSERT_TRUE(plain);
    EXPECT_EQ(plain->status, 200);
    EXPECT_EQ(plain->body, want);
    EXPECT_FALSE(plain->has_header("Content-Encoding"));
    const std::string etag = plain->get_header_value("ETag");
    EXPECT_EQ(etag.size(), 34u) << etag;
    EXPECT_EQ(plain->get_header_value("Cache-Control"), "no-cache");
    for (const std::string coding : {"br", "gzip"}) {
      const auto res = get(http(), path, coding == "br" ? "gzip, deflate, br" : "gzip;q=1.0, br;q=0");
      ASSERT_TRUE(res);
      EXPECT_EQ(res->status, 200);
      if (want.size() > 1000) {
        EXPECT_EQ(res->get_header_value("Content-Encoding"), coding);
        EXPECT_EQ(res->get_header_value_count("Content-Encoding"), 1u) << "compressed once, not again";
        EXPECT_LT(std::stoull(res->get_header_value("Content-Length")), want.size());
      }
      EXPECT_EQ(res->body, want) << coding << " decodes to the file";
      EXPECT_EQ(res->get_header_value("ETag"), etag) << "one validator for every encoding of the same bytes";
      EXPECT_EQ(res->get_header_value("Vary"), "Accept-Encoding");
    }
    const auto again = get(http(), path, "br", etag);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->status, 304);
    EXPECT_TRUE(again->body.empty());
    const auto stale = get(http(), path, "br", "\"0000\"");
    ASSERT_TRUE(stale);
    EXPECT_EQ(stale->status, 200);
  }
  EXPECT_EQ(get(http(), "/favicon.ico", "identity")->get_header_value("Content-Type"), "image/svg+xml");
}

}  // namespace
}  // namespace voxd::test
