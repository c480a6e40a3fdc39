#pragma once
// A multipart/form-data body (RFC 7578, RFC 2046 §5.1) read as it arrives:
// each part's name and filename, then its bytes, in the pieces they came
// in. cpp-httplib 0.11 reads multipart bodies with a parser of its own that
// copies and searches the body a byte at a time through a std::string, a
// fifth of the service's CPU on a small job (docs/benchmarks.md, issue #39);
// this one searches with memchr and memcmp, hands a part's bytes on from the
// chunk they arrived in, and keeps back only what may be the start of a
// delimiter (or of a header line) until the next chunk.
//
// What it accepts is what httplib's parser did, so clients see no change:
// a preamble before the first "--boundary\r\n" is skipped; a part's header
// lines end at an empty line; Content-Disposition gives the part's name and
// filename (other headers are skipped); the body ends with
// "\r\n--boundary--", after which anything (the epilogue) is ignored. A
// header line over kMaxHeaderLine bytes, or a delimiter followed by neither
// "\r\n" nor "--", is malformed.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace voxd::server {

class MultipartReader {
 public:
  struct Part {
    std::string name, filename;
  };
  // Either returns false to stop reading (the reader then reports false).
  using OnPart = std::function<bool(const Part&)>;
  using OnData = std::function<bool(const char* data, std::size_t size)>;

  static constexpr std::size_t kMaxHeaderLine = 8192;  // httplib's CPPHTTPLIB_HEADER_MAX_LENGTH

  MultipartReader(std::string_view boundary, OnPart on_part, OnData on_data);

  // Reads the next piece of the body. False: the body is malformed, or a
  // callback stopped it; nothing more is read after.
  bool feed(const char* data, std::size_t size);
  // Whether the closing delimiter has been read: a body that ends before it
  // is truncated.
  bool complete() const { return state_ == State::done; }

 private:
  enum class State { preamble, headers, body, after_delimiter, done, failed };
  // Reads what it can of `in` from `at`; returns where it stopped (what is
  // left is kept for the next piece), or npos when it failed.
  std::size_t read(std::string_view in, std::size_t at);
  bool header_line(std::string_view line);

  std::string first_delimiter_;  // "--boundary\r\n"
  std::string delimiter_;        // "\r\n--boundary"
  OnPart on_part_;
  OnData on_data_;
  State state_ = State::preamble;
  Part part_;
  std::string kept_;  // the end of the last piece, not yet read
};

// The boundary parameter of a multipart Content-Type (quoted or not), or
// nothing when it has none, or one that is empty or longer than RFC 2046's
// 70 characters.
std::optional<std::string> multipart_boundary(std::string_view content_type);

}  // namespace voxd::server
