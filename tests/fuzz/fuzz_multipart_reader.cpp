// libFuzzer harness for the service's multipart/form-data reader
// (server/http/multipart_reader.h): the first byte picks the boundary, the
// second the size of the pieces the body arrives in, the rest is the body.
// After each input:
//   - read in pieces or all at once, the reader gives the same parts (names,
//     filenames, bytes) and the same verdicts (stopped, complete): what a
//     client sends does not depend on how TCP cut it;
//   - no part's bytes hold the delimiter ("\r\n--" and the boundary), and a
//     complete body holds the closing delimiter;
//   - and ASan/UBSan: no crash, no leak, no undefined behaviour.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/multipart_reader.h"

namespace {

using voxd::server::MultipartReader;

struct Reading {
  std::vector<std::string> parts;  // name, filename, bytes, for each part
  bool fed = true, complete = false;
  bool operator==(const Reading&) const = default;
};

Reading read(std::string_view boundary, std::string_view body, std::size_t piece) {
  Reading r;
  bool bytes_before_a_part = false;
  MultipartReader reader(
      boundary,
      [&](const MultipartReader::Part& p) {
        r.parts.insert(r.parts.end(), {p.name, p.filename, ""});
        return true;
      },
      [&](const char* data, std::size_t n) {
        if (r.parts.empty() || n == 0) bytes_before_a_part = true;
        else r.parts.back().append(data, n);
        return true;
      });
  for (std::size_t at = 0; at < body.size() && r.fed; at += piece)
    r.fed = reader.feed(body.data() + at, std::min(piece, body.size() - at));
  r.complete = reader.complete();
  if (bytes_before_a_part) std::abort();  // data before any part's headers, or an empty piece
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  static const std::string_view boundaries[] = {"b", "--", "fuzz boundary", "------------------------a1b2c3d4e5f60718"};
  const std::string_view boundary = boundaries[data[0] % 4];
  const std::size_t piece = 1 + data[1] % 64;
  const std::string_view body(reinterpret_cast<const char*>(data + 2), size - 2);
  const Reading whole = read(boundary, body, body.size() + 1);
  const Reading pieces = read(boundary, body, piece);
  if (!(whole == pieces)) std::abort();
  const std::string delimiter = "\r\n--" + std::string(boundary);
  for (std::size_t i = 2; i < whole.parts.size(); i += 3)
    if (whole.parts[i].find(delimiter) != std::string::npos) std::abort();
  if (whole.complete && body.find(delimiter + "--") == std::string_view::npos) std::abort();
  return 0;
}
