#include "server/http/multipart_reader.h"

#include <algorithm>
#include <cctype>

namespace voxd::server {
namespace {

constexpr std::string_view kCrlf = "\r\n";

bool lower_equal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

bool starts_with_lower(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && lower_equal(s.substr(0, prefix.size()), prefix);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// The next parameter of a header value after `at` (from the next ';'): its
// name and value, a quoted string or a token up to the next ';'. Not every
// client escapes a quote inside a quoted filename (httplib's client writes
// it as it is; browsers write %22), so a quoted value ends at the first
// quote followed by ';' or the end, as httplib's parser read it: the
// filename `<b>"odd" part.stl` arrives whole.
bool next_parameter(std::string_view v, std::size_t& at, std::string_view& name, std::string_view& value) {
  std::size_t semicolon = v.find(';', at), equals;
  for (;; semicolon = v.find(';', semicolon + 1)) {  // past parameters with no value
    if (semicolon == std::string_view::npos) return false;
    equals = v.find('=', semicolon + 1);
    if (equals == std::string_view::npos) return false;
    if (equals < v.find(';', semicolon + 1)) break;
  }
  name = trim(v.substr(semicolon + 1, equals - semicolon - 1));
  std::size_t start = equals + 1;
  while (start < v.size() && (v[start] == ' ' || v[start] == '\t')) ++start;
  if (start < v.size() && v[start] == '"') {
    std::size_t close = start;
    for (;;) {  // to the first quote followed by ';' or the end (see above)
      close = v.find('"', close + 1);
      if (close == std::string_view::npos) return false;
      std::size_t after = close + 1;
      while (after < v.size() && (v[after] == ' ' || v[after] == '\t')) ++after;
      if (after == v.size() || v[after] == ';') break;
    }
    value = v.substr(start + 1, close - start - 1);
    at = close + 1;
  } else {
    const std::size_t end = std::min(v.find(';', start), v.size());
    value = trim(v.substr(start, end - start));
    at = end;
  }
  return true;
}

}  // namespace

MultipartReader::MultipartReader(std::string_view boundary, OnPart on_part, OnData on_data)
    : first_delimiter_("--" + std::string(boundary) + "\r\n"),
      delimiter_("\r\n--" + std::string(boundary)),
      on_part_(std::move(on_part)),
      on_data_(std::move(on_data)) {}

bool MultipartReader::feed(const char* data, std::size_t size) {
  if (state_ == State::failed) return false;
  if (state_ == State::done) return true;  // the epilogue
  std::size_t left;
  if (kept_.empty()) {
    const std::string_view in(data, size);
    left = read(in, 0);
    if (left != std::string_view::npos) kept_.assign(in.substr(left));
  } else {
    // What was kept is short (part of a delimiter or of a header line), so
    // a piece is copied behind it rather than read in two places.
    kept_.append(data, size);
    left = read(kept_, 0);
    if (left != std::string_view::npos) kept_.erase(0, left);
  }
  if (left == std::string_view::npos) {
    state_ = State::failed;
    kept_.clear();
    return false;
  }
  if (state_ == State::done) kept_.clear();
  return true;
}

std::size_t MultipartReader::read(std::string_view in, std::size_t at) {
  constexpr std::size_t kFailed = std::string_view::npos;
  for (;;) {
    switch (state_) {
      case State::preamble: {
        const std::size_t found = in.find(first_delimiter_, at);
        if (found == std::string_view::npos) {
          // Keep what may be the delimiter's start; the rest is preamble.
          const std::size_t keep = first_delimiter_.size() - 1;
          return in.size() - at > keep ? in.size() - keep : at;
        }
        at = found + first_delimiter_.size();
        part_ = {};
        state_ = State::headers;
        break;
      }
      case State::headers: {
        const std::size_t end = in.find(kCrlf, at);
        // A line at the limit may be waiting for the LF of its CRLF.
        if (end == std::string_view::npos) return in.size() - at > kMaxHeaderLine + 1 ? kFailed : at;
        if (end - at > kMaxHeaderLine) return kFailed;
        const std::string_view line = in.substr(at, end - at);
        at = end + kCrlf.size();
        if (line.empty()) {
          if (!on_part_(part_)) return kFailed;
          state_ = State::body;
        } else if (!header_line(line)) {
          return kFailed;
        }
        break;
      }
      case State::body: {
        const std::size_t found = in.find(delimiter_, at);
        if (found != std::string_view::npos) {
          if (found > at && !on_data_(in.data() + at, found - at)) return kFailed;
          at = found + delimiter_.size();
          state_ = State::after_delimiter;
          break;
        }
        // Every byte is the part's but those that may start a delimiter:
        // from the first CR among the last delimiter-less-one bytes.
        const std::size_t window = in.size() > delimiter_.size() - 1 ? in.size() - (delimiter_.size() - 1) : 0;
        const std::size_t end = std::min(in.find('\r', std::max(at, window)), in.size());
        if (end > at && !on_data_(in.data() + at, end - at)) return kFailed;
        return end;
      }
      case State::after_delimiter: {
        if (in.size() - at < 2) return at;
        const std::string_view next = in.substr(at, 2);
        if (next == kCrlf) {
          at += 2;
          part_ = {};
          state_ = State::headers;
        } else if (next == "--") {
          state_ = State::done;
          return in.size();
        } else {
          return kFailed;  // the boundary string inside a part: the client chose a bad boundary
        }
        break;
      }
      case State::done:
        return in.size();
      case State::failed:
        return kFailed;
    }
  }
}

bool MultipartReader::header_line(std::string_view line) {
  constexpr std::string_view kDisposition = "content-disposition:";
  if (!starts_with_lower(line, kDisposition)) return true;  // Content-Type and the like: not needed
  const std::string_view value = trim(line.substr(kDisposition.size()));
  if (!starts_with_lower(value, "form-data")) return true;
  std::size_t at = 0;
  std::string_view name, parameter;
  while (next_parameter(value, at, name, parameter)) {
    if (lower_equal(name, "name")) part_.name = parameter;
    else if (lower_equal(name, "filename")) part_.filename = parameter;
  }
  return true;
}

std::optional<std::string> multipart_boundary(std::string_view content_type) {
  // The parameters after the media type: "multipart/form-data; boundary=...".
  std::size_t at = 0;
  std::string_view name, value;
  while (next_parameter(content_type, at, name, value))
    if (lower_equal(name, "boundary"))
      return value.empty() || value.size() > 70 ? std::nullopt : std::optional<std::string>(value);
  return std::nullopt;
}

}  // namespace voxd::server
