// `voxd submit`: the CLI as a client of a running voxd service. The same job
// flags and output flags as `voxd voxelize`; the job runs on the service,
// its progress shows on a terminal, and its volume is written where -o says.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "api/error_table.h"
#include "api/job_params.h"
#include "server/cli/cli.h"
#include "server/cli/cli_args.h"
#include "server/cli/cli_output.h"
#include "server/cli/cli_params.h"
#include "server/mapped_file.h"
#include "voxd/error.h"

namespace voxd::cli {
namespace {

using nlohmann::json;

constexpr const char* kUsage = R"(usage: voxd submit MESH -o OUT [options]

Submits MESH to a running voxd service as a job, follows its progress (a bar
on a terminal), and writes the job's volume to OUT ("-" for standard output).
The job runs on the service, with its limits; the flags are voxd voxelize's.

  --server URL           the service (default: $VOXD_SERVER, else
                         http://127.0.0.1:8080)
  --api-key KEY          its API key (default: $VOXD_API_KEY)
  --params JSON|@FILE    job parameters, the same JSON the HTTP API takes
  --name NAME            the job's name in the service's lists (default:
                         MESH's file name)
  --tags JSON            tags, a JSON object of strings: {"project": "pump"}
  --callback URL         a URL the service calls (signed) when the job ends;
                         its host must be in the service's allow-list
  --analysis KIND[?QUERY]  an analysis the service makes with the job, as
                         its route takes it: analysis?min_wall=1.5,
                         radiography?axis=z, section?axis=x&index=40,
                         preview, thickness?format=ply; repeat for several.
                         Each is written beside OUT as OUT's name, the kind
                         and its format's extension (OUT.analysis.json), or
                         into --analyses-dir DIR
  --resolution N, --voxel-size H, --origin X,Y,Z, --dims NX,NY,NZ,
  --padding P, --mode M, --inside T, --units U, --streaming S, --device D
                         as for voxd voxelize (they override --params; the
                         service's GPU is what device cuda needs)
  --format F             {formats}
                         (default: from OUT's extension)
  --raw-packing P, --nrrd-encoding E, --quantize Q
                         as for voxd voxelize
  --report               include the mesh report in the summary
  --json                 print the summary (the job's final status and the
                         output) as JSON on standard output (on standard
                         error when OUT is -)
  --no-progress          no progress bar, even on a terminal

Exit status as voxd voxelize's: 0 done, 2 a usage, parameter or limit
error, 1 anything else (a bad mesh, a failed or cancelled job, a service
that cannot be reached or is busy past its retries). Errors are one line on
standard error that starts with the problem type the service answered.
)";

// An error answer of the service (or a failed job's error): its problem.
struct ServiceProblem : std::runtime_error {
  ServiceProblem(std::string slug, std::string message, int exit_code)
      : std::runtime_error(std::move(message)), slug(std::move(slug)), exit_code(exit_code) {}
  std::string slug;
  int exit_code;
};

// The CLI exit status of a problem type: the error table's, else 1.
int exit_code_of(const std::string& slug) {
  for (const api::ErrorKind& kind : api::error_table())
    if (slug == kind.slug) return kind.cli_exit;
  return slug == "malformed-json" || slug == "params-too-large" ? api::kExitUsage : api::kExitFailure;
}

ServiceProblem problem_of(const json& problem, int status) {
  const std::string type = problem.value("type", "");
  std::string slug = type.substr(type.rfind(':') == std::string::npos ? 0 : type.rfind(':') + 1);
  if (slug.empty()) slug = "http-" + std::to_string(status);
  std::string message = problem.value("detail", problem.value("title", "HTTP " + std::to_string(status)));
  if (problem.contains("errors") && problem["errors"].is_array())
    for (const json& e : problem["errors"]) message += "; " + e.value("path", "") + ": " + e.value("message", "");
  return ServiceProblem(slug, message, exit_code_of(slug));
}

// Why a request got no answer, in words (httplib's own names are one word:
// "Connection").
std::string no_answer(httplib::Error error) {
  switch (error) {
    case httplib::Error::Connection:
      return "cannot connect: the connection was refused, or nothing answers there (is voxd serving at --server?)";
    case httplib::Error::ConnectionTimeout:
      return "cannot connect: no answer within the connection timeout";
    case httplib::Error::Read:
      return "the connection broke (or timed out) while reading the answer";
    case httplib::Error::Write:
      return "the connection broke (or timed out) while sending the request";
    case httplib::Error::BindIPAddress:
      return "cannot bind the local address";
    default:
      return "no answer (" + httplib::to_string(error) + ")";
  }
}

ServiceProblem problem_of(const httplib::Result& res, const std::string& what) {
  if (!res) return ServiceProblem("unreachable", what + ": " + no_answer(res.error()), api::kExitFailure);
  try {
    return problem_of(json::parse(res->body), res->status);
  } catch (const json::exception&) {
    return ServiceProblem("http-" + std::to_string(res->status), what + ": HTTP " + std::to_string(res->status),
                          api::kExitFailure);
  }
}

// --analysis KIND[?QUERY]: the job JSON's analyses entry, its fields as the
// route's query has them (the service reads strings as the route does).
json analysis_entry(const std::string& spec) {
  const std::size_t q = spec.find('?');
  const std::string kind = spec.substr(0, q);
  if (!value_named(api::kAnalysisKindNames, kind))
    throw UsageError("--analysis " + spec + ": the kind must be one of " + names_joined(api::kAnalysisKindNames, ", ", " or "));
  json entry = {{"kind", kind}};
  if (q == std::string::npos) return entry;
  std::stringstream query(spec.substr(q + 1));
  for (std::string pair; std::getline(query, pair, '&');) {
    if (pair.empty()) continue;
    const std::size_t eq = pair.find('=');
    if (eq == std::string::npos || eq == 0) throw UsageError("--analysis " + spec + ": each query part must be name=value");
    entry[pair.substr(0, eq)] = pair.substr(eq + 1);
  }
  return entry;
}

// Where the analyses go: DIR/STEM or OUT without its extension ("part" for
// part.rle); "voxd-JOB" in the working directory for OUT "-".
std::string analyses_stem(const std::string& out, const std::optional<std::string>& dir) {
  std::string name = out == "-" ? std::string("voxd") : out.substr(out.find_last_of('/') == std::string::npos ? 0 : out.find_last_of('/') + 1);
  if (const std::size_t dot = name.rfind('.'); dot != std::string::npos && dot > 0) name.resize(dot);
  if (dir) return *dir + "/" + name;
  const std::size_t slash = out.find_last_of('/');
  return out == "-" || slash == std::string::npos ? name : out.substr(0, slash + 1) + name;
}

std::string extension_of(const std::string& content_type) {
  if (content_type.rfind("application/json", 0) == 0) return "json";
  if (content_type.rfind("image/png", 0) == 0) return "png";
  if (content_type.rfind("model/gltf-binary", 0) == 0) return "glb";
  if (content_type.rfind("application/x-nrrd", 0) == 0) return "nrrd";
  if (content_type.rfind("model/stl", 0) == 0) return "stl";
  if (content_type.find("ply") != std::string::npos) return "ply";
  return "bin";
}

class ServiceClient {
 public:
  static constexpr std::size_t kMaxEventBytes = std::size_t{1} << 20;

  ServiceClient(const std::string& url, std::string api_key) : url_(url), api_key_(std::move(api_key)) {
    while (!url_.empty() && url_.back() == '/') url_.pop_back();
    if (url.rfind("http://", 0) != 0)
      throw UsageError("--server must be an http:// URL (put TLS in front of voxd with a proxy), got '" + url + "'");
    client_ = std::make_unique<httplib::Client>(url);
    client_->set_connection_timeout(10);
    client_->set_read_timeout(60);  // the event stream sends a keep-alive every 15 s
    client_->set_write_timeout(60);
  }

  httplib::Headers headers() const {
    httplib::Headers h = {{"User-Agent", "voxd-submit"}};
    if (!api_key_.empty()) h.emplace("Authorization", "Bearer " + api_key_);
    return h;
  }

  // A request retried while the service says it is busy (429/503 with
  // Retry-After), a few times.
  template <typename Send>
  httplib::Result with_retries(Send send) {
    for (int attempt = 0;; ++attempt) {
      httplib::Result res = send();
      if (!res || (res->status != 429 && res->status != 503) || attempt == 5) return res;
      const int wait = std::clamp(std::atoi(res->get_header_value("Retry-After").c_str()), 1, 60);
      std::this_thread::sleep_for(std::chrono::seconds(wait));
    }
  }

  // `labels`: the job's name, tags and callback, as the parts the API takes.
  json submit(const std::string& mesh, const std::string& filename, const json& params,
              const std::vector<std::pair<std::string, std::string>>& labels) {
    httplib::MultipartFormDataItems items = {{"mesh", mesh, filename, "application/octet-stream"},
                                             {"params", params.dump(), "", "application/json"}};
    for (const auto& [part, value] : labels) items.push_back({part, value, "", "text/plain"});
    auto res = with_retries([&] { return client_->Post("/v1/jobs", headers(), items); });
    if (!res || (res->status != 200 && res->status != 202)) throw problem_of(res, "POST " + url_ + "/v1/jobs");
    return json::parse(res->body);
  }

  json status(const std::string& id) {
    auto res = with_retries([&] { return client_->Get("/v1/jobs/" + id, headers()); });
    if (!res || res->status != 200) throw problem_of(res, "GET " + url_ + "/v1/jobs/" + id);
    return json::parse(res->body);
  }

  // Follows the job's events, calling `on_change` with each state; returns
  // the final status, or nullopt when the stream broke off (poll instead).
  template <typename OnChange>
  std::optional<json> follow(const std::string& id, OnChange on_change) {
    std::string buffer;
    json now = {{"id", id}};
    std::optional<json> final;
    auto handle_block = [&](const std::string& block) {
      std::string name, data;
      std::istringstream lines(block);
      for (std::string line; std::getline(lines, line);) {
        if (line.rfind("event: ", 0) == 0) name = line.substr(7);
        else if (line.rfind("data: ", 0) == 0) data += line.substr(6);
      }
      if (name.empty() || data.empty()) return;
      const json d = json::parse(data, nullptr, false);
      if (d.is_discarded()) return;
      if (name == "job" || name == "end") now = d;
      else if (name == "state" || name == "progress") now.update(d);
      else if (name == "gone") throw ServiceProblem("not-found", "job " + id + " was deleted or has expired", api::kExitFailure);
      on_change(now);
      if (name == "end") final = now;
    };
    httplib::Headers h = headers();
    h.emplace("Accept", "text/event-stream");
    auto res = client_->Get(
        "/v1/jobs/" + id + "/events", h, [&](const httplib::Response& r) { return r.status == 200; },
        [&](const char* data, std::size_t n) {
          buffer.append(data, n);
          for (std::size_t cut; (cut = buffer.find("\n\n")) != std::string::npos;) {
            handle_block(buffer.substr(0, cut));
            buffer.erase(0, cut + 2);
          }
          // voxd's events are a few KB: a stream that sends this much
          // without ending an event is not one, and is left for polling.
          if (buffer.size() > kMaxEventBytes) {
            std::cerr << "voxd submit: the event stream sent over " << (kMaxEventBytes >> 20)
                      << " MiB without ending an event; polling instead\n";
            return false;
          }
          return !final.has_value();
        });
    return final;
  }

  // The volume into OUT; its byte count.
  std::uint64_t download(const std::string& id, const OutputChoice& output) {
    std::string query = "format=" + std::string(to_string(output.format));
    if (output.options.raw_packing == RawPacking::bits) query += "&packing=bits";
    if (output.options.nrrd_encoding == NrrdEncoding::gzip) query += "&encoding=gzip";
    if (output.options.quantize == Quantize::u8) query += "&quantize=u8";
    if (output.options.quantize == Quantize::u16) query += "&quantize=u16";
    return write_output(output.path, [&](ByteSink& sink) {
      std::string error_body;
      int status = 0;
      auto res = with_retries([&] {
        error_body.clear();
        return client_->Get(
            "/v1/jobs/" + id + "/volume?" + query, headers(),
            [&](const httplib::Response& r) {
              status = r.status;
              return true;
            },
            [&](const char* data, std::size_t n) {
              if (status == 200) sink.write(reinterpret_cast<const std::uint8_t*>(data), n);
              else if (error_body.size() < kMaxEventBytes) error_body.append(data, std::min(n, kMaxEventBytes));
              return true;
            });
      });
      if (!res || res->status != 200) {
        if (res) res->body = error_body;
        throw problem_of(res, "GET " + url_ + "/v1/jobs/" + id + "/volume");  // write_output removes the partial file
      }
    });
  }

  // Each of the job's analyses, fetched from its URL into STEM.KIND.EXT
  // (STEM.KIND-N.EXT when a kind comes twice); what was written.
  json download_analyses(const json& job, const std::string& stem) {
    json written = json::array();
    if (!job.contains("analyses") || !job["analyses"].is_array()) return written;
    std::map<std::string, int> seen;
    for (const json& entry : job["analyses"]) {
      const std::string url = entry.value("url", "");
      const std::string kind = entry.contains("request") ? entry["request"].value("kind", "analysis") : "analysis";
      if (entry.value("state", "") == "failed")
        throw ServiceProblem("analysis-failed", "the job's " + kind + " failed: " + entry.value("error", std::string()), api::kExitFailure);
      auto res = with_retries([&] { return client_->Get(url, headers()); });
      if (!res || res->status != 200) throw problem_of(res, "GET " + url_ + url);
      const int n = ++seen[kind];
      const std::string path = stem + "." + kind + (n > 1 ? "-" + std::to_string(n) : "") + "." + extension_of(res->get_header_value("Content-Type"));
      write_output(path, [&](ByteSink& sink) { sink.write(reinterpret_cast<const std::uint8_t*>(res->body.data()), res->body.size()); });
      written.push_back({{"kind", kind}, {"url", url}, {"path", path}, {"bytes", res->body.size()}});
    }
    return written;
  }

 private:
  std::string url_;
  std::string api_key_;
  std::unique_ptr<httplib::Client> client_;
};

// "[#########           ]  45% voxelize", redrawn in place on a terminal.
class ProgressBar {
 public:
  explicit ProgressBar(bool on) : on_(on) {}
  ~ProgressBar() { finish(); }
  void show(const json& status) {
    if (!on_) return;
    const double p = std::clamp(status.value("progress", 0.0), 0.0, 1.0);
    const std::string state = status.value("state", "");
    std::string stage = state == "running" && status.contains("stage") && status["stage"].is_string()
                            ? status["stage"].get<std::string>() : state;
    const int filled = static_cast<int>(p * 30 + 0.5);
    char line[160];
    std::snprintf(line, sizeof line, "\r[%s%s] %3d%% %-28.28s", std::string(filled, '#').c_str(),
                  std::string(30 - filled, ' ').c_str(), static_cast<int>(p * 100 + 0.5), stage.c_str());
    std::cerr << line << std::flush;
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::cerr << '\n';
    drawn_ = false;
  }

 private:
  bool on_;
  bool drawn_ = false;
};

int submit(int argc, char** argv) {
  std::set<std::string> valued(std::begin(kParamFlags), std::end(kParamFlags));
  valued.insert(std::begin(kOutputFlags), std::end(kOutputFlags));
  valued.insert({"server", "api-key", "streaming", "device", "name", "tags", "callback", "analysis", "analyses-dir"});
  Args args(argc, argv, 2, valued, {"json", "report", "no-progress", "help"});
  if (args.has("help")) {
    std::cout << with_format_list(kUsage);
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("submit takes exactly one mesh file (see voxd submit --help)");
  const OutputChoice output = read_output_choice(args, "submit");
  json params = load_params(args);
  apply_param_flags(args, params);
  for (const std::string& spec : args.values("analysis")) {
    if (!params.contains("analyses")) params["analyses"] = json::array();
    params["analyses"].push_back(analysis_entry(spec));
  }
  if (auto s = args.value("streaming")) params["streaming"] = *s;
  // The service checks both again; this says what is wrong before any upload.
  const api::JobParams parsed = api::parse_job_params(params);
  if (auto refusal = parsed.format_refusal(output.format, output.options))
    throw UsageError("mode " + parsed.mode_name() + ": " + *refusal);

  const char* env_server = std::getenv("VOXD_SERVER");
  const char* env_key = std::getenv("VOXD_API_KEY");
  const std::string server = args.value("server").value_or(env_server && *env_server ? env_server : "http://127.0.0.1:8080");
  ServiceClient client(server, args.value("api-key").value_or(env_key ? env_key : ""));

  const std::string& mesh_path = args.positional()[0];
  MappedFile file(mesh_path);
  const auto bytes = file.bytes();
  const std::string filename = mesh_path.substr(mesh_path.find_last_of('/') == std::string::npos ? 0 : mesh_path.find_last_of('/') + 1);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::pair<std::string, std::string>> labels;
  for (const char* label : {"name", "tags", "callback"})
    if (auto v = args.value(label)) labels.emplace_back(label, *v);
  json job = client.submit(std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), filename, params, labels);
  const std::string id = job.at("id");

  ProgressBar bar(!args.has("no-progress") && isatty(STDERR_FILENO));
  const std::string state = job.value("state", "");
  if (state != "succeeded" && state != "failed" && state != "cancelled") {
    std::optional<json> final = client.follow(id, [&](const json& s) { bar.show(s); });
    // No stream (an older service, a proxy that buffers): poll.
    for (auto wait = std::chrono::milliseconds(200); !final; wait = std::min(wait * 3 / 2, std::chrono::milliseconds(5000))) {
      json s = client.status(id);
      bar.show(s);
      const std::string st = s.value("state", "");
      if (st == "succeeded" || st == "failed" || st == "cancelled") final = s;
      else std::this_thread::sleep_for(wait);
    }
    job = *final;
  }
  bar.finish();
  if (job.value("state", "") == "failed") {
    const json error = job.contains("error") && job["error"].is_object() ? job["error"] : json::object();
    throw problem_of(error, error.value("status", 500));
  }
  if (job.value("state", "") == "cancelled") throw ServiceProblem("cancelled", "job " + id + " was cancelled", api::kExitFailure);

  const std::uint64_t written = client.download(id, output);
  const json analyses = client.download_analyses(job, analyses_stem(output.path, args.value("analyses-dir")));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  json summary = {{"server", server},
                  {"job", id},
                  {"mesh", {{"path", mesh_path}, {"format", job.value("mesh_format", "")}, {"triangles", job.value("triangles", 0)}}},
                  {"grid", job.value("grid", json())},
                  {"mode", job.at("params").value("mode", "solid")},
                  {"filled_voxels", job.value("filled_voxels", json())},
                  {"filled_volume", job.value("filled_volume", json())},
                  {"streamed", job.value("streamed", false)},
                  {"execution", job.value("execution", "memory")},
                  {"cached", job.value("cached", false)},
                  {"values", job.value("values", json())},
                  {"inside", job.value("inside", json())},
                  {"warnings", job.value("warnings", json::array())},
                  {"timings", job.value("timings", json::object())},
                  {"output", {{"path", output.path}, {"format", to_string(output.format)}, {"bytes", written}}},
                  {"seconds", seconds}};
  if (args.has("report")) summary["report"] = job.value("mesh", json());
  if (!analyses.empty()) summary["analyses"] = analyses;
  std::ostream& out = output.path == "-" ? std::cerr : std::cout;
  if (args.has("json")) {
    out << summary.dump(2) << '\n';
  } else {
    std::ostringstream s;
    const json& g = summary["grid"];
    s << "job:     " << id << " on " << server << (summary["cached"].get<bool>() ? " (answered from an identical job)" : "") << '\n';
    if (g.is_object())
      s << "grid:    " << g["dims"][0] << " x " << g["dims"][1] << " x " << g["dims"][2] << " voxels of " << g["voxel_size"] << '\n';
    s << "filled:  " << summary["filled_voxels"] << " voxels, volume " << summary["filled_volume"] << '\n';
    if (args.has("report")) s << "mesh report: " << summary["report"].dump() << '\n';
    s << "output:  " << output.path << " (" << to_string(output.format) << ", " << written << " bytes), " << seconds << " s\n";
    for (const json& a : analyses) s << "analysis: " << a.value("path", "") << " (" << a.value("bytes", 0) << " bytes)\n";
    for (const json& w : summary["warnings"])
      s << "warning: " << w.value("message", "") << " [" << w.value("code", "") << "]\n";
    std::cerr << s.str();
  }
  return 0;
}

}  // namespace

int submit_command(int argc, char** argv) {
  try {
    return submit(argc, argv);
  } catch (const ServiceProblem& e) {
    std::cerr << "voxd: " << e.slug << ": " << e.what() << '\n';
    return e.exit_code;
  }
}

}  // namespace voxd::cli
