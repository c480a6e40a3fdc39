// MultipartReader (server/http/multipart_reader.h) against bodies built
// here part by part: whatever pieces the body arrives in, the parts come
// out with their names, filenames and exact bytes, a body cut anywhere
// before its closing delimiter is incomplete, and what is malformed or
// refused stops the read.
#include "server/http/multipart_reader.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace voxd::server {
namespace {

struct ReadPart {
  std::string name, filename, bytes;
  bool operator==(const ReadPart&) const = default;
};

struct BodyPart {
  std::string headers;  // the part's header lines, each ending in CRLF
  std::string bytes;
};

const std::string kBoundary = "------------------------a1b2c3d4e5f60718";

std::string body_of(const std::vector<BodyPart>& parts, const std::string& boundary = kBoundary,
                    const std::string& preamble = "", const std::string& epilogue = "\r\n") {
  std::string body = preamble;
  for (const BodyPart& p : parts) body += "--" + boundary + "\r\n" + p.headers + "\r\n" + p.bytes + "\r\n";
  return body + "--" + boundary + "--" + epilogue;
}

struct Reading {
  std::vector<ReadPart> parts;
  bool fed = true, complete = false;
};

// Reads `body` in pieces of `piece` bytes (the last one shorter).
Reading read_in_pieces(const std::string& body, std::size_t piece, const std::string& boundary = kBoundary) {
  Reading r;
  MultipartReader reader(
      boundary,
      [&](const MultipartReader::Part& p) {
        r.parts.push_back({p.name, p.filename, ""});
        return true;
      },
      [&](const char* data, std::size_t n) {
        if (r.parts.empty()) return false;  // bytes before any part: the reader's bug
        r.parts.back().bytes.append(data, n);
        return true;
      });
  for (std::size_t at = 0; at < body.size() && r.fed; at += piece)
    r.fed = reader.feed(body.data() + at, std::min(piece, body.size() - at));
  r.complete = reader.complete();
  return r;
}

// A mesh's bytes that look like the delimiter's start again and again: CRs,
// "\r\n--", and the boundary less its last character.
std::string tricky_bytes() {
  std::string bytes;
  for (int i = 0; i < 300; ++i) bytes += static_cast<char>((i * 37) & 0xFF);
  bytes += "\r\r\n\r\n-\r\n--\r\n--" + kBoundary.substr(0, kBoundary.size() - 1) + "\r\n--" + kBoundary.substr(1);
  bytes += "--" + kBoundary + "\r";  // the boundary without its CRLF before it is data
  for (int i = 0; i < 300; ++i) bytes += (i % 3 == 0) ? '\r' : static_cast<char>(i & 0xFF);
  return bytes + "\r\n-";
}

const std::vector<BodyPart>& submission_parts() {
  static const std::vector<BodyPart> parts = {
      {"Content-Disposition: form-data; name=\"mesh\"; filename=\"part one.stl\"\r\nContent-Type: "
       "application/octet-stream\r\n",
       tricky_bytes()},
      {"Content-Disposition: form-data; name=\"params\"\r\n", R"({"grid": {"resolution": 64}})"},
      {"content-disposition: FORM-DATA; name=tags\r\n", ""},
      {"Content-Type: text/plain\r\n", "no disposition"},
  };
  return parts;
}

std::vector<ReadPart> expected_parts() {
  return {{"mesh", "part one.stl", tricky_bytes()},
          {"params", "", R"({"grid": {"resolution": 64}})"},
          {"tags", "", ""},
          {"", "", "no disposition"}};
}

TEST(MultipartReader, ReadsEveryPartWhateverPiecesTheBodyComesIn) {
  const std::string body = body_of(submission_parts(), kBoundary, "a preamble\r\n", "\r\nan epilogue\r\n");
  for (std::size_t piece : {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{5}, std::size_t{41},
                            std::size_t{42}, std::size_t{43}, std::size_t{64}, std::size_t{4096}, body.size()}) {
    const Reading r = read_in_pieces(body, piece);
    EXPECT_TRUE(r.fed) << piece;
    EXPECT_TRUE(r.complete) << piece;
    EXPECT_EQ(r.parts, expected_parts()) << "pieces of " << piece;
  }
}

TEST(MultipartReader, ABodyCutBeforeItsClosingDelimiterIsIncomplete) {
  const std::string body = body_of(submission_parts());
  const std::size_t closing = body.rfind("--" + kBoundary + "--");
  // Every cut up to the closing delimiter's last "--" leaves it incomplete.
  for (std::size_t cut = 0; cut < closing + kBoundary.size() + 4; ++cut) {
    const Reading r = read_in_pieces(body.substr(0, cut), 7);
    EXPECT_TRUE(r.fed) << cut;
    EXPECT_FALSE(r.complete) << "cut at " << cut << " of " << body.size();
  }
  EXPECT_TRUE(read_in_pieces(body.substr(0, closing + kBoundary.size() + 4), 7).complete);
}

TEST(MultipartReader, AQuotedBoundaryAndAnEmptyBodyPart) {
  const std::string boundary = "simple boundary";
  const std::string body = body_of({{"Content-Disposition: form-data; name=\"mesh\"; filename=\"\"\r\n", ""}}, boundary);
  const Reading r = read_in_pieces(body, 3, *multipart_boundary("multipart/form-data; boundary=\"simple boundary\""));
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(r.parts, (std::vector<ReadPart>{{"mesh", "", ""}}));
}

TEST(MultipartReader, AHeaderLineOverTheLimitIsMalformed) {
  const std::string long_header = "X-Long: " + std::string(MultipartReader::kMaxHeaderLine, 'x') + "\r\n";
  const std::string body = body_of({{long_header + "Content-Disposition: form-data; name=\"mesh\"\r\n", "abc"}});
  for (std::size_t piece : {std::size_t{100}, body.size()}) {
    const Reading r = read_in_pieces(body, piece);
    EXPECT_FALSE(r.fed) << piece;
    EXPECT_FALSE(r.complete);
    EXPECT_TRUE(r.parts.empty());
  }
  // A line of the limit's length is a header like any other, however it is
  // cut (the largest pieces end between its CR and LF).
  const std::string fits = "X-Long: " + std::string(MultipartReader::kMaxHeaderLine - 8, 'x') + "\r\n";
  const std::string fits_body = body_of({{fits + "Content-Disposition: form-data; name=\"mesh\"\r\n", "abc"}});
  for (std::size_t piece : {std::size_t{1}, std::size_t{100}, kBoundary.size() + 4 + MultipartReader::kMaxHeaderLine + 1}) {
    const Reading r = read_in_pieces(fits_body, piece);
    EXPECT_TRUE(r.complete) << piece;
    EXPECT_EQ(r.parts, (std::vector<ReadPart>{{"mesh", "", "abc"}})) << piece;
  }
}

TEST(MultipartReader, ADelimiterFollowedByNeitherCrlfNorDashesIsMalformed) {
  const std::string body = "--" + kBoundary + "\r\nContent-Disposition: form-data; name=\"mesh\"\r\n\r\nabc\r\n--" +
                           kBoundary + "xyz\r\nmore\r\n--" + kBoundary + "--\r\n";
  const Reading r = read_in_pieces(body, 5);
  EXPECT_FALSE(r.fed);
  EXPECT_FALSE(r.complete);
  ASSERT_EQ(r.parts.size(), 1u);
  EXPECT_EQ(r.parts[0].bytes, "abc");
}

TEST(MultipartReader, ACallbackThatStopsEndsTheRead) {
  const std::string body = body_of(submission_parts());
  int parts = 0, pieces = 0;
  MultipartReader reader(
      kBoundary,
      [&](const MultipartReader::Part&) {
        ++parts;
        return true;
      },
      [&](const char*, std::size_t) { return ++pieces < 3; });
  bool fed = true;
  for (std::size_t at = 0; at < body.size() && fed; at += 16) fed = reader.feed(body.data() + at, std::min<std::size_t>(16, body.size() - at));
  EXPECT_FALSE(fed);
  EXPECT_EQ(pieces, 3);
  EXPECT_EQ(parts, 1);
  EXPECT_FALSE(reader.feed(body.data(), 1)) << "a stopped reader reads nothing more";
  EXPECT_FALSE(reader.complete());
}

TEST(MultipartReader, NoDelimiterAtAllIsIncomplete) {
  const Reading r = read_in_pieces(std::string(10000, '-') + "\r\n", 999);
  EXPECT_TRUE(r.fed);
  EXPECT_FALSE(r.complete);
  EXPECT_TRUE(r.parts.empty());
}

TEST(MultipartBoundary, FromTheContentType) {
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary=abc"), "abc");
  EXPECT_EQ(multipart_boundary("multipart/form-data;boundary=\"a b;c\""), "a b;c");
  EXPECT_EQ(multipart_boundary("multipart/form-data; charset=utf-8; Boundary=xyz; other=1"), "xyz");
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary=" + std::string(70, 'b')), std::string(70, 'b'));
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary=" + std::string(71, 'b')), std::nullopt);
  EXPECT_EQ(multipart_boundary("multipart/form-data"), std::nullopt);
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary="), std::nullopt);
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary=\"\""), std::nullopt);
  EXPECT_EQ(multipart_boundary("multipart/form-data; boundary=\"unclosed"), std::nullopt);
  EXPECT_EQ(multipart_boundary("multipart/form-data; novalue; boundary=b"), "b");
}

// A quote in a quoted filename, as httplib's client sends it (unescaped):
// the value ends at the quote before the next ';' or the line's end.
TEST(MultipartReader, AQuoteInsideAFilenameIsPartOfIt) {
  const std::string body =
      body_of({{"Content-Disposition: form-data; name=\"mesh\"; filename=\"<b>\"odd\" part.stl\" \r\n", "x"},
               {"Content-Disposition: form-data; name=\"a\"b\"; filename=\"c;d\"\r\n", "y"}});
  const Reading r = read_in_pieces(body, 9);
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(r.parts, (std::vector<ReadPart>{{"mesh", "<b>\"odd\" part.stl", "x"}, {"a\"b", "c;d", "y"}}));
}

}  // namespace
}  // namespace voxd::server
