#include "server/http/submission.h"

#include <utility>

#include "server/http/metrics.h"
#include "server/http/multipart_reader.h"
#include "server/http/route_table.h"
#include "voxd/encode/number_text.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

using nlohmann::json;
using httplib::Request;

constexpr std::size_t kMaxLabelPartBytes = 64 * 1024;

ProblemError params_too_large(std::size_t limit) {
  return ProblemError(make_problem(413, "params-too-large", "Job parameters too large",
                                   "the job parameters are over the limit of " + std::to_string(limit) +
                                       " bytes; custom palettes and lookups fit well within it"));
}

json parse_params_text(const std::string& text, const api::JsonLimits& limits) {
  if (text.empty()) return json::object();
  try {
    return api::parse_bounded_json(text, "params", limits);
  } catch (const api::InvalidJson& e) {
    if (e.reason() == api::InvalidJson::Reason::too_large) throw params_too_large(limits.max_bytes);
    throw ProblemError(make_problem(400, "malformed-json", "Malformed job parameters", e.what()));
  }
}

ProblemError unsupported_media_type() {
  return ProblemError(make_problem(415, "unsupported-media-type", "Unsupported content type",
                                   "send the mesh as multipart/form-data (parts mesh and params) or as the raw "
                                   "request body (e.g. application/octet-stream) with params in the query string"));
}

// Reads the body as it was sent, multipart or not. httplib 0.11 reads a
// body whose Content-Type says multipart/form-data with its own parser
// whatever the handler asks for, a byte at a time (MultipartReader says
// what that cost); only a body it does not take for multipart reaches the
// handler's receiver as sent. The request is httplib's own object, not a
// const one (handlers get a const reference to it), so its Content-Type is
// set aside for the read and put back after it.
bool read_body_as_sent(const Request& req, const httplib::ContentReader& reader,
                       const httplib::ContentReceiver& receive) {
  auto& headers = const_cast<Request&>(req).headers;
  const auto type = headers.find("Content-Type");
  if (type == headers.end()) return reader(receive);
  struct PutBack {
    std::string& value;
    std::string original;
    ~PutBack() { value = std::move(original); }
  } put_back{type->second, std::exchange(type->second, "application/octet-stream")};
  return reader(receive);
}

}  // namespace

std::optional<std::uint64_t> declared_length(const httplib::Request& req) {
  if (!req.has_header("Content-Length")) return std::nullopt;
  const std::string v = req.get_header_value("Content-Length");
  return parse_number<std::uint64_t>(v).value_or(UINT64_MAX);
}

ProblemError upload_too_large(std::uint64_t limit) {
  return ProblemError(make_problem(413, "upload-too-large", "Upload too large",
                                   "the request body is over the limit of " + std::to_string(limit) +
                                       " bytes; send a smaller mesh (Draco compresses meshes about 10x)"));
}

Submission read_submission(const httplib::Request& req, const httplib::ContentReader& reader, Metrics& metrics,
                           std::uint64_t max_bytes, const api::JsonLimits& params_limits) {
  Submission s;
  const std::string type = req.get_header_value("Content-Type");
  if (declared_length(req).value_or(0) > max_bytes)
    throw upload_too_large(max_bytes);
  std::uint64_t received = 0;
  auto count = [&](std::size_t n) {
    received += n;
    metrics.add_bytes_in(n);
    return received <= max_bytes;
  };
  bool read_ok = true;
  if (req.is_multipart_form_data()) {
    const std::optional<std::string> boundary = multipart_boundary(type);
    if (!boundary) {
      set_body_consumed(false);
      throw ProblemError(make_problem(400, "bad-request", "Bad request",
                                      "the multipart/form-data Content-Type has no boundary parameter (1 to 70 "
                                      "characters), so its parts cannot be found"));
    }
    enum class Part { mesh, params, label, other } part = Part::other;
    std::string params_text;
    std::optional<std::string>* label = nullptr;
    bool has_mesh = false, has_params = false, params_over_limit = false, label_over_limit = false;
    MultipartReader parts(
        *boundary,
        [&](const MultipartReader::Part& header) {
          if (header.name == "mesh") {
            part = Part::mesh;
            has_mesh = true;
            s.filename = header.filename;
            s.mesh.clear();
            // The mesh is most of the body: one buffer of its size, not a
            // doubling series of copies.
            if (!req.has_header("Content-Encoding")) s.mesh.reserve(declared_length(req).value_or(0));
          } else if (header.name == "params") {
            part = Part::params;
            has_params = true;
            params_text.clear();
          } else if (header.name == "name" || header.name == "tags" || header.name == "callback") {
            part = Part::label;
            label = header.name == "name" ? &s.name : header.name == "tags" ? &s.tags : &s.callback;
            label->emplace();
          } else {
            part = Part::other;
          }
          return true;
        },
        [&](const char* data, std::size_t n) {
          if (part == Part::mesh) {
            s.mesh.insert(s.mesh.end(), data, data + n);
          } else if (part == Part::params) {
            // Stop reading past the limit instead of holding the whole part.
            if (params_text.size() + n > params_limits.max_bytes) {
              params_over_limit = true;
              return false;
            }
            params_text.append(data, n);
          } else if (part == Part::label) {
            // Labels are short: a part past 64 KiB is refused as it crosses it.
            if ((*label)->size() + n > kMaxLabelPartBytes) {
              label_over_limit = true;
              return false;
            }
            (*label)->append(data, n);
          }
          return true;
        });
    read_ok = read_body_as_sent(req, reader, [&](const char* data, std::size_t n) {
      return count(n) && parts.feed(data, n);
    }) && parts.complete();
    if (read_ok && !has_mesh)
      throw ProblemError(make_problem(400, "missing-mesh", "No mesh uploaded",
                                      "the multipart body has no part named \"mesh\"; send the mesh file in it"));
    if (label_over_limit) {
      set_body_consumed(false);
      throw ProblemError(make_problem(413, "params-too-large", "Job label too large",
                                      "a name, tags or callback part is over " + std::to_string(kMaxLabelPartBytes) +
                                          " bytes; a name takes at most 256, each tag 256"));
    }
    if (params_over_limit) {
      set_body_consumed(false);
      throw params_too_large(params_limits.max_bytes);
    }
    s.params = has_params ? parse_params_text(params_text, params_limits) : json::object();
  } else {
    if (type.rfind("application/json", 0) == 0 || type.rfind("text/", 0) == 0 || type.rfind("multipart/", 0) == 0)
      throw unsupported_media_type();
    // One buffer of the declared size rather than a doubling series of
    // copies (gzip bodies grow past it as they are unpacked).
    if (!req.has_header("Content-Encoding")) s.mesh.reserve(declared_length(req).value_or(0));
    read_ok = reader([&](const char* data, std::size_t n) {
      if (!count(n)) return false;
      s.mesh.insert(s.mesh.end(), data, data + n);
      return true;
    });
    s.filename = req.get_param_value("filename");
    for (const auto& [field, label] : {std::pair{"name", &s.name}, {"tags", &s.tags}, {"callback", &s.callback}})
      if (req.has_param(field)) *label = req.get_param_value(field);
    if (read_ok) s.params = parse_params_text(req.get_param_value("params"), params_limits);
  }
  set_body_consumed(read_ok);
  if (!read_ok && received > max_bytes) throw upload_too_large(max_bytes);
  if (!read_ok)
    throw ProblemError(make_problem(400, "bad-request", "Bad request",
                                    "the request body could not be read completely (truncated, malformed multipart or timed out)"));
  // An empty file is an empty mesh, as the CLI and the error table have it
  // (empty_input: 422 invalid-mesh, with the decoder's words); a multipart
  // body with no mesh part at all is the 400 missing-mesh above.
  if (s.mesh.empty()) throw Error(ErrorCode::empty_input, "the mesh file is empty (0 bytes); upload it again");
  return s;
}

}  // namespace voxd::server
