#include "server/http/http_api.h"

#include <charconv>
#include <chrono>
#include <optional>
#include <random>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "api/bounded_json.h"
#include "api/job_params.h"
#include "api/param_error.h"
#include "api/result_json.h"
#include "server/http/analysis_routes.h"
#include "server/http/connection_server.h"
#include "server/http/problem.h"
#include "server/job_pipeline.h"
#include "server/http/mode_routes.h"
#include "server/log_safe.h"
#include "server/http/volume_stream.h"
#include "server/jobs/job_record.h"

namespace voxd::server {
namespace {

using nlohmann::json;
using httplib::Request;
using httplib::Response;

const char* const kJobId = R"(([0-9a-f]{32}))";

struct RequestClock {
  std::chrono::steady_clock::time_point start;
  std::string request_id;
};
thread_local RequestClock current_request;
// Whether the current request's body was read to its end, so an error answer
// can keep the connection open (nothing of the body is left on it).
thread_local bool body_consumed = false;

std::string new_request_id() {
  thread_local std::mt19937_64 rng{std::random_device{}()};
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(rng()));
  return buf;
}

void send_json(Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

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

struct Submission {
  std::vector<std::uint8_t> mesh;
  std::string filename;
  json params;
};

ProblemError unsupported_media_type() {
  return ProblemError(make_problem(415, "unsupported-media-type", "Unsupported content type",
                                   "send the mesh as multipart/form-data (parts mesh and params) or as the raw "
                                   "request body (e.g. application/octet-stream) with params in the query string"));
}

// A job submission is either multipart/form-data (mesh + params parts) or the
// raw mesh as the body with params in the query string. The body is read here,
// through httplib's content reader, not by httplib before routing: that keeps
// `curl --data-binary` (sent as application/x-www-form-urlencoded) from being
// parsed as a form, and counts the bytes as they arrive.
// The declared body size, or UINT64_MAX for a value that is not a number
// (httplib itself refuses those before the body is read).
std::optional<std::uint64_t> declared_length(const Request& req) {
  if (!req.has_header("Content-Length")) return std::nullopt;
  const std::string v = req.get_header_value("Content-Length");
  std::uint64_t n = 0;
  const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
  if (ec != std::errc() || end != v.data() + v.size()) return UINT64_MAX;
  return n;
}

ProblemError upload_too_large(std::uint64_t limit) {
  return ProblemError(make_problem(413, "upload-too-large", "Upload too large",
                                   "the request body is over the limit of " + std::to_string(limit) +
                                       " bytes; send a smaller mesh (Draco compresses meshes about 10x)"));
}

Submission read_submission(const Request& req, const httplib::ContentReader& reader, Metrics& metrics,
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
    enum class Part { mesh, params, other } part = Part::other;
    std::string params_text;
    bool has_mesh = false, has_params = false, params_over_limit = false;
    read_ok = reader(
        [&](const httplib::MultipartFormData& header) {
          if (header.name == "mesh") {
            part = Part::mesh;
            has_mesh = true;
            s.filename = header.filename;
            s.mesh.clear();
          } else if (header.name == "params") {
            part = Part::params;
            has_params = true;
            params_text.clear();
          } else {
            part = Part::other;
          }
          return true;
        },
        [&](const char* data, std::size_t n) {
          if (!count(n)) return false;
          if (part == Part::mesh) {
            s.mesh.insert(s.mesh.end(), data, data + n);
          } else if (part == Part::params) {
            // Stop reading past the limit instead of holding the whole part.
            if (params_text.size() + n > params_limits.max_bytes) {
              params_over_limit = true;
              return false;
            }
            params_text.append(data, n);
          }
          return true;
        });
    if (read_ok && !has_mesh)
      throw ProblemError(make_problem(400, "missing-mesh", "No mesh uploaded",
                                      "the multipart body has no part named \"mesh\"; send the mesh file in it"));
    if (params_over_limit) {
      body_consumed = false;
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
    if (read_ok) s.params = parse_params_text(req.get_param_value("params"), params_limits);
  }
  body_consumed = read_ok;
  if (!read_ok && received > max_bytes) throw upload_too_large(max_bytes);
  if (!read_ok)
    throw ProblemError(make_problem(400, "bad-request", "Bad request",
                                    "the request body could not be read completely (truncated, malformed multipart or timed out)"));
  if (s.mesh.empty())
    throw ProblemError(make_problem(400, "missing-mesh", "No mesh uploaded", "the uploaded mesh is empty"));
  return s;
}

struct VolumeRequest {
  VolumeFormat format = VolumeFormat::rle;
  EncodeOptions options;
};

VolumeRequest read_volume_request(const Request& req) {
  VolumeRequest v;
  if (req.has_param("format")) {
    const auto f = volume_format_from_string(req.get_param_value("format"));
    if (!f)
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                      "format must be rle, binvox, raw, nrrd, vox, png-stack, stl or glb, got '" +
                                          req.get_param_value("format") + "'"));
    v.format = *f;
  }
  if (req.has_param("quantize")) {
    const std::string q = req.get_param_value("quantize");
    if (q == "u8") v.options.quantize = Quantize::u8;
    else if (q == "u16") v.options.quantize = Quantize::u16;
    else if (q != "none")
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", "quantize must be none, u8 or u16, got '" + q + "'"));
  }
  if (req.has_param("encoding")) {
    const std::string e = req.get_param_value("encoding");
    if (v.format != VolumeFormat::nrrd)
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                      "encoding applies to format nrrd only (for compression in transit send Accept-Encoding: gzip)"));
    if (e == "gzip") v.options.nrrd_encoding = NrrdEncoding::gzip;
    else if (e != "raw")
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", "encoding must be raw or gzip, got '" + e + "'"));
  }
  if (req.has_param("packing")) {
    const std::string p = req.get_param_value("packing");
    if (p == "bits") v.options.raw_packing = RawPacking::bits;
    else if (p != "bytes")
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", "packing must be bytes or bits, got '" + p + "'"));
  }
  return v;
}

// What a job's volume holds, for the NRRD "content:" line.
std::string volume_content(const JobSnapshot& job) {
  if (!job.has_value_volume()) return "voxels (1 = filled)";
  const json& values = job.values;
  std::string text = values.value("quantity", "values");
  if (values.contains("unit")) text += " (" + values.at("unit").get<std::string>();
  if (values.contains("sign_convention")) text += ", " + values.at("sign_convention").get<std::string>();
  if (values.contains("unit")) text += ")";
  return text;
}

void refuse_quantized_bits(const VolumeRequest& v) {
  if (v.options.quantize != Quantize::none)
    throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                    "quantize applies to float values (a volume of type f32); this volume is bits"));
}

// Refuses a format that cannot hold a value job's values before any work.
void check_format_holds(const api::JobParams& params, const VolumeRequest& v) {
  if (params.mode->writes(v.format)) return;
  const std::optional<ValueVolume> probe = params.value_type();
  if (!probe) {
    refuse_quantized_bits(v);
    if (auto refusal = format_refusal(BitVolume(), v.format))
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", *refusal));
    return;
  }
  if (auto refusal = format_refusal(*probe, v.format, v.options))
    throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", *refusal));
}

// The volumes of a synchronous job's output, which is never stored.
api::VolumeSource sync_volumes(const JobOutput& output) {
  return [output](const std::string& name) -> std::shared_ptr<const ValueVolume> {
    if (name == "values") return output.values;
    for (const auto& [layer, volume] : output.layers)
      if (layer == name) return volume;
    throw std::logic_error("a synchronous job has no layer " + name);
  };
}

bool accepts_gzip(const Request& req) {
  return req.get_header_value("Accept-Encoding").find("gzip") != std::string::npos;
}

std::size_t query_size(const Request& req, const char* name, std::size_t fallback, std::size_t lo, std::size_t hi) {
  if (!req.has_param(name)) return fallback;
  const std::string v = req.get_param_value(name);
  try {
    std::size_t pos = 0;
    const unsigned long long n = std::stoull(v, &pos);
    if (pos == v.size() && n >= lo && n <= hi && v.find('-') == std::string::npos) return n;
  } catch (const std::exception&) {
  }
  throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter",
                                  std::string(name) + " must be an integer between " + std::to_string(lo) + " and " +
                                      std::to_string(hi) + ", got '" + v + "'"));
}

bool constant_time_equal(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

// Route label for metrics: the pattern, not the concrete path (bounded cardinality).
std::string route_of(const std::string& path) {
  if (path.rfind("/v1/jobs/", 0) == 0) return path.size() > 41 ? "/v1/jobs/{id}" + path.substr(41) : "/v1/jobs/{id}";
  static const char* known[] = {"/v1/jobs", "/v1/voxelize", "/healthz", "/readyz", "/metrics", "/openapi.json"};
  for (const char* k : known)
    if (path == k) return k;
  return "other";
}

}  // namespace

void HttpApi::install(httplib::Server& server) {
  // Wraps a handler: exceptions become problems, never crashes.
  auto answer_exception = [this](const Request& req, Response& res) {
    const Problem p = problem_from_current_exception();
    // Rejections are counted by their problem type, the same words clients see.
    if ((p.status >= 400 && p.status < 500) || p.status == 503) metrics_.count_rejected(p.slug);
    send_problem(res, p, req.path);
  };
  auto guarded = [answer_exception](auto handler) -> httplib::Server::Handler {
    return [answer_exception, handler](const Request& req, Response& res) {
      try {
        handler(req, res);
      } catch (...) {
        answer_exception(req, res);
      }
    };
  };
  auto guarded_upload = [answer_exception](auto handler) -> httplib::Server::HandlerWithContentReader {
    return [answer_exception, handler](const Request& req, Response& res, const httplib::ContentReader& reader) {
      body_consumed = false;
      try {
        handler(req, res, reader);
      } catch (...) {
        // A refused upload may be left partly unread: then the connection
        // cannot carry another request, and is closed after the answer (the
        // rest of the body must never be read as further requests).
        if (!body_consumed) {
          res.set_header("Connection", "close");
          close_connection_after_response();
        }
        answer_exception(req, res);
      }
    };
  };

  server.set_pre_routing_handler([this](const Request& req, Response& res) {
    begin_request_body();  // the head is parsed: the body's deadline applies from here
    current_request.start = std::chrono::steady_clock::now();
    const std::string client_id = req.get_header_value("X-Request-Id");
    current_request.request_id = is_plain_request_id(client_id) ? client_id : new_request_id();
    res.set_header("X-Request-Id", current_request.request_id);
    // CORS for allowed web front ends.
    const std::string origin = req.get_header_value("Origin");
    bool cors = false;
    if (!origin.empty())
      for (const auto& o : config_.cors_origins) cors = cors || o == "*" || o == origin;
    if (cors) {
      res.set_header("Access-Control-Allow-Origin", origin);
      res.set_header("Vary", "Origin");
      res.set_header("Access-Control-Expose-Headers", "Location, Retry-After, X-Request-Id, X-Voxd-Job-Id, X-Voxd-Dims, X-Voxd-Filled-Voxels, X-Voxd-Value-Type");
      if (req.method == "OPTIONS" && req.has_header("Access-Control-Request-Method")) {
        res.set_header("Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
        res.set_header("Access-Control-Allow-Headers", "Authorization, Content-Type, X-Request-Id");
        res.set_header("Access-Control-Max-Age", "600");
        res.status = 204;
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    // Optional API keys on the /v1 routes; probes and metrics stay open.
    if (!config_.api_keys.empty() && req.path.rfind("/v1/", 0) == 0) {
      const std::string auth = req.get_header_value("Authorization");
      bool ok = false;
      if (auth.rfind("Bearer ", 0) == 0)
        for (const auto& key : config_.api_keys) ok = constant_time_equal(auth.substr(7), key) || ok;
      if (!ok) {
        metrics_.count_rejected("unauthorized");
        res.set_header("WWW-Authenticate", "Bearer");
        send_problem(res, make_problem(401, "unauthorized", "Unauthorized", "this service needs an API key: send Authorization: Bearer KEY"), req.path);
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });

  // Clients that ask before sending a body (curl does for large uploads) learn
  // at once that it is too large.
  server.set_expect_100_continue_handler([this](const Request& req, Response& res) {
    if (declared_length(req).value_or(0) > config_.max_upload_bytes) {
      metrics_.count_rejected("upload-too-large");
      send_problem(res, upload_too_large(config_.max_upload_bytes).problem(), req.path);
      res.set_header("Connection", "close");
      close_connection_after_response();
      return 413;
    }
    return 100;
  });

  // Errors httplib produces itself (unknown route, body over the limit,
  // unparsable request) get problem bodies too.
  server.set_error_handler([this](const Request& req, Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 404)
      send_problem(res, make_problem(404, "not-found", "Not found", "no route " + req.method + " " + req.path), req.path);
    else if (res.status == 413) {
      close_connection_after_response();  // httplib left the body unread
      metrics_.count_rejected("upload-too-large");
      send_problem(res, make_problem(413, "upload-too-large", "Upload too large",
                                     "the request body is over the limit of " + std::to_string(config_.max_upload_bytes) + " bytes"),
                   req.path);
    } else
      send_problem(res, make_problem(res.status, "bad-request", "Bad request", "the request could not be read"), req.path);
  });

  server.set_logger([this](const Request& req, const Response& res) {
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - current_request.start).count();
    metrics_.count_request(req.method, route_of(req.path), res.status);
    metrics_.add_bytes_out(res.body.size());
    if (config_.log_format == "json")
      spdlog::info(json{{"event", "request"}, {"method", req.method}, {"path", req.path}, {"status", res.status},
                        {"bytes", res.body.size()}, {"duration_ms", ms}, {"request_id", current_request.request_id}}
                       // Paths are not always UTF-8: replace, never throw.
                       .dump(-1, ' ', false, json::error_handler_t::replace));
    else
      spdlog::info("{} {} {} {}B {:.1f}ms id={}", log_safe(req.method), log_safe(req.path), res.status, res.body.size(), ms,
                   current_request.request_id);
  });

  // Wrong methods on known routes: 405 with Allow, not a misleading 404.
  auto allow_only = [&](const std::string& pattern, const std::string& allow) {
    auto refuse = [allow](const Request& req, Response& res) {
      res.set_header("Allow", allow);
      send_problem(res, make_problem(405, "method-not-allowed", "Method not allowed",
                                     req.method + " is not allowed on " + req.path + "; allowed: " + allow),
                   req.path);
    };
    if (allow.find("GET") == std::string::npos) server.Get(pattern, refuse);
    if (allow.find("POST") == std::string::npos) server.Post(pattern, refuse);
    if (allow.find("DELETE") == std::string::npos) server.Delete(pattern, refuse);
    server.Put(pattern, refuse);
    server.Patch(pattern, refuse);
  };

  server.Get("/healthz", [](const Request&, Response& res) { send_json(res, 200, {{"status", "ok"}}); });
  server.Get("/readyz", [this](const Request&, Response& res) {
    if (draining_ || !jobs_.accepting()) return send_json(res, 503, {{"status", "not ready"}, {"reason", "shutting down"}});
    if (jobs_.counts().queue_depth >= config_.queue_size)
      return send_json(res, 503, {{"status", "not ready"}, {"reason", "the job queue is full"}});
    if (!jobs_.storage_ok())
      return send_json(res, 503, {{"status", "not ready"}, {"reason", "the data directory's disk is full"}});
    send_json(res, 200, {{"status", "ready"}});
  });
  server.Get("/metrics", [this](const Request&, Response& res) {
    res.set_content(metrics_.render(jobs_.counts()), "text/plain; version=0.0.4; charset=utf-8");
  });
  server.Get("/openapi.json", [](const Request&, Response& res) { res.set_content(kOpenApiDocument, "application/json"); });
  for (const char* p : {"/healthz", "/readyz", "/metrics", "/openapi.json"}) allow_only(p, "GET");

  server.Post("/v1/jobs", guarded_upload([this](const Request& req, Response& res, const httplib::ContentReader& reader) {
    Submission s = read_submission(req, reader, metrics_, config_.max_upload_bytes, params_limits_);
    const JobSnapshot job = jobs_.submit(std::move(s.mesh), s.filename, s.params);
    res.set_header("Location", "/v1/jobs/" + job.id);
    send_json(res, 202, to_json(job));
  }));
  server.Get("/v1/jobs", guarded([this](const Request& req, Response& res) {
    const std::size_t offset = query_size(req, "offset", 0, 0, std::size_t{1} << 40);
    const std::size_t limit = query_size(req, "limit", 20, 1, 100);
    std::size_t total = 0;
    json list = json::array();
    for (const auto& job : jobs_.list(offset, limit, &total)) list.push_back(to_json(job));
    const bool more = offset + limit < total;
    send_json(res, 200, {{"jobs", list}, {"total", total}, {"offset", offset}, {"limit", limit},
                         {"next", more ? json("/v1/jobs?offset=" + std::to_string(offset + limit) + "&limit=" + std::to_string(limit)) : json(nullptr)}});
  }));
  allow_only("/v1/jobs", "GET, POST");

  const std::string job_path = std::string("/v1/jobs/") + kJobId;
  auto unknown_job = [](const std::string& id) {
    return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
  };
  server.Get(job_path, guarded([this, unknown_job](const Request& req, Response& res) {
    const auto job = jobs_.get(req.matches[1]);
    if (!job) throw unknown_job(req.matches[1]);
    send_json(res, 200, to_json(*job));
  }));
  server.Delete(job_path, guarded([this, unknown_job](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    switch (jobs_.cancel_or_delete(id)) {
      case JobManager::RemoveResult::not_found: throw unknown_job(id);
      case JobManager::RemoveResult::deleted: res.status = 204; return;
      case JobManager::RemoveResult::cancelled: {
        const auto job = jobs_.get(id);
        send_json(res, 202, job ? to_json(*job) : json{{"id", id}, {"state", "cancelled"}});
        return;
      }
    }
  }));
  allow_only(job_path, "GET, DELETE");

  server.Get(job_path + "/volume", guarded([this, unknown_job](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const VolumeRequest v = read_volume_request(req);
    const auto job = jobs_.get(id);
    if (!job) throw unknown_job(id);
    if (job->state != JobState::succeeded)
      throw ProblemError(make_problem(409, "job-not-finished", "The job has no volume yet",
                                      std::string("the job is ") + to_string(job->state) + "; its volume exists once it has succeeded"));
    VolumeRequest request = v;
    request.options.content = volume_content(*job);
    const std::string filename = id + file_extension(v.format);
    const api::JobParams& params = *job->job;
    if (params.mode->writes(v.format)) {
      return stream_encoded(
          res, media_type(v.format),
          [volumes = volumes_of(jobs_, *job), job = job->job, format = v.format](ByteSink& sink) {
            job->mode->write(format, *job, volumes, sink);
          },
          accepts_gzip(req), filename, &metrics_);
    }
    if (req.has_param("layer")) {
      auto layer = job_layer(jobs_, *job, req.get_param_value("layer"));
      if (auto refusal = format_refusal(*layer, v.format, v.options))
        throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", *refusal));
      res.set_header("X-Voxd-Value-Type", value_type_name(*layer));
      return stream_volume(res, std::move(layer), v.format, request.options, accepts_gzip(req), filename, &metrics_);
    }
    if (job->has_value_volume()) {
      auto values = jobs_.values(id);
      if (!values) throw unknown_job(id);
      if (auto refusal = format_refusal(*values, v.format, v.options))
        throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", *refusal));
      res.set_header("X-Voxd-Value-Type", value_type_name(*values));
      return stream_volume(res, std::move(values), v.format, request.options, accepts_gzip(req), filename, &metrics_);
    }
    refuse_quantized_bits(v);
    if (auto refusal = format_refusal(BitVolume(), v.format))
      throw ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", *refusal));
    auto volume = jobs_.volume(id);
    if (!volume) throw unknown_job(id);
    res.set_header("X-Voxd-Value-Type", "bit");
    stream_volume(res, std::move(volume), v.format, request.options, accepts_gzip(req), filename, &metrics_);
  }));
  allow_only(job_path + "/volume", "GET");

  for (const std::string& pattern : install_analysis_routes(server, jobs_, job_path, [guarded](PlainHandler h) { return guarded(h); }))
    allow_only(pattern, "GET");
  for (const std::string& pattern : install_mode_routes(server, jobs_, job_path, [guarded](PlainHandler h) { return guarded(h); }))
    allow_only(pattern, "GET");

  server.Post("/v1/voxelize", guarded_upload([this](const Request& req, Response& res, const httplib::ContentReader& reader) {
    const VolumeRequest v = read_volume_request(req);
    Submission s = read_submission(req, reader, metrics_, config_.max_upload_bytes, params_limits_);
    const api::JobParams params = api::parse_job_params(s.params);
    check_format_holds(params, v);  // before any work
    JobSnapshot job;
    // A client that gives up on the answer cancels the job.
    JobOutput output =
        jobs_.run_sync(std::move(s.mesh), s.filename, s.params, &job, config_.sync_max_voxels, request_client_gone);
    if (!output.solid) {
      Problem p = job.failure ? make_problem(job.failure->type == "internal" ? 500 : 422, job.failure->type, job.failure->title, job.failure->detail)
                              : make_problem(409, "cancelled", "The job was cancelled", "the job was cancelled");
      throw ProblemError(p);
    }
    res.set_header("X-Voxd-Job-Id", job.id);
    res.set_header("X-Voxd-Dims", std::to_string(job.grid.dims.x) + "," + std::to_string(job.grid.dims.y) + "," + std::to_string(job.grid.dims.z));
    res.set_header("X-Voxd-Filled-Voxels", std::to_string(job.filled_voxels.value_or(0)));
    VolumeRequest request = v;
    request.options.content = volume_content(job);
    const std::string filename = "voxels" + std::string(file_extension(v.format));
    if (output.values && params.mode->writes(v.format)) {
      return stream_encoded(
          res, media_type(v.format),
          [output, job = job.job, format = v.format](ByteSink& sink) {
            job->mode->write(format, *job, sync_volumes(output), sink);
          },
          accepts_gzip(req), filename, &metrics_);
    }
    if (output.values) {
      res.set_header("X-Voxd-Value-Type", value_type_name(*output.values));
      return stream_volume(res, std::move(output.values), v.format, request.options, accepts_gzip(req), filename, &metrics_);
    }
    res.set_header("X-Voxd-Value-Type", "bit");
    stream_volume(res, std::move(output.solid), v.format, request.options, accepts_gzip(req), filename, &metrics_);
  }));
  allow_only("/v1/voxelize", "POST");
}

}  // namespace voxd::server
