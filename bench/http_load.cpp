// Load generator for voxd serve on loopback: C keep-alive connections, each
// sending jobs back to back for a fixed time; reports throughput and latency
// percentiles, and samples the server's resident memory (a soak shows whether
// it stays flat).
//
//   http_load --port P[,P2,...] --mesh FILE --params JSON [--flow sync|async]
//             [--connections C] [--seconds S] [--server-pid PID] [--json]
//
// sync:  POST /v1/voxelize (multipart), the volume comes back in the answer.
// async: POST /v1/jobs, poll GET /v1/jobs/ID until it ends, GET its volume;
//        the latency is the whole round trip a client sees.
// Several ports (replicas on one Redis): connection t talks to port t mod n.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>
#include <nlohmann/json.hpp>

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  int port = 0;
  std::vector<int> ports;
  std::string mesh_path;
  std::string params = R"({"grid":{"resolution":64}})";
  std::string flow = "sync";
  int connections = 4;
  double seconds = 10;
  int server_pid = 0;
  bool json = false;
};

// CPU time the hypervisor gave to others while we wanted it (the "st" of
// vmstat), from the aggregate line of /proc/stat: a loaded shared VM shows
// it in every latency figure, so the report states it.
struct CpuTimes {
  double busy = 0, steal = 0, total = 0;
};
CpuTimes cpu_times() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  double v[8] = {};
  in >> cpu;
  for (double& x : v) in >> x;
  CpuTimes t;
  for (double x : v) t.total += x;
  t.steal = v[7];
  t.busy = t.total - v[3] - v[4];
  return t;
}

long rss_kib(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}

// Says why a job failed, for the first few failures: an error in a
// benchmark is a finding, not noise.
bool failed(const char* step, const httplib::Result& r) {
  static std::atomic<int> told{0};
  if (told++ < 5)
    std::cerr << "http_load: " << step << ": " << (r ? std::to_string(r->status) + " " + r->body.substr(0, 300) : "no response")
              << "\n";
  return false;
}

// One job as a client sees it; returns false on any error.
bool run_one(httplib::Client& c, const Options& o, const std::string& mesh) {
  httplib::MultipartFormDataItems items = {{"mesh", mesh, "part.stl", "application/octet-stream"},
                                           {"params", o.params, "", "application/json"}};
  if (o.flow == "sync") {
    auto r = c.Post("/v1/voxelize", items);
    return (r && r->status == 200 && !r->body.empty()) || failed("POST /v1/voxelize", r);
  }
  auto r = c.Post("/v1/jobs", items);
  if (!r || r->status != 202) return failed("POST /v1/jobs", r);
  const std::string id = nlohmann::json::parse(r->body).at("id");
  for (;;) {
    auto s = c.Get(("/v1/jobs/" + id).c_str());
    if (!s || s->status != 200) return failed("GET /v1/jobs/ID", s);
    const std::string state = nlohmann::json::parse(s->body).at("state");
    if (state == "succeeded") break;
    if (state == "failed" || state == "cancelled") return failed("the job ended", s);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  auto v = c.Get(("/v1/jobs/" + id + "/volume").c_str());
  if (!v || v->status != 200) return failed("GET /v1/jobs/ID/volume", v);
  // Clean up as a batch client would, so a soak measures the service, not
  // an ever-growing store.
  auto d = c.Delete(("/v1/jobs/" + id).c_str());
  return (d && d->status == 204) || failed("DELETE /v1/jobs/ID", d);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "http_load: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--port") {
      std::stringstream list(next());
      for (std::string p; std::getline(list, p, ',');) o.ports.push_back(std::stoi(p));
      o.port = o.ports.empty() ? 0 : o.ports.front();
    }
    else if (a == "--mesh") o.mesh_path = next();
    else if (a == "--params") o.params = next();
    else if (a == "--flow") o.flow = next();
    else if (a == "--connections") o.connections = std::stoi(next());
    else if (a == "--seconds") o.seconds = std::stod(next());
    else if (a == "--server-pid") o.server_pid = std::stoi(next());
    else if (a == "--json") o.json = true;
    else {
      std::cerr << "http_load: unknown option " << a << "\n";
      return 2;
    }
  }
  if (o.port == 0 || o.mesh_path.empty() || (o.flow != "sync" && o.flow != "async")) {
    std::cerr << "usage: http_load --port P --mesh FILE [--params JSON] [--flow sync|async] [--connections C] [--seconds S] "
                 "[--server-pid PID] [--json]\n";
    return 2;
  }
  std::ifstream in(o.mesh_path, std::ios::binary);
  const std::string mesh((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  std::mutex mutex;
  std::vector<double> latencies_ms;
  std::atomic<long> errors{0};
  std::vector<std::pair<double, long>> rss;  // (seconds, KiB)
  const CpuTimes cpu0 = cpu_times();
  const auto start = Clock::now();
  const auto until = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds));
  std::atomic<bool> done{false};
  std::thread sampler([&] {
    while (!done) {
      if (o.server_pid) rss.emplace_back(std::chrono::duration<double>(Clock::now() - start).count(), rss_kib(o.server_pid));
      for (int i = 0; i < 10 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  std::vector<std::thread> clients;
  for (int t = 0; t < o.connections; ++t)
    clients.emplace_back([&, t] {
      httplib::Client c("127.0.0.1", o.ports[static_cast<std::size_t>(t) % o.ports.size()]);
      c.set_keep_alive(true);
      c.set_tcp_nodelay(true);
      c.set_read_timeout(60, 0);
      std::vector<double> mine;
      while (Clock::now() < until) {
        const auto t0 = Clock::now();
        if (run_one(c, o, mesh)) mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        else ++errors;
      }
      std::lock_guard lock(mutex);
      latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
    });
  for (auto& c : clients) c.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  done = true;
  sampler.join();
  if (o.server_pid) rss.emplace_back(elapsed, rss_kib(o.server_pid));

  const CpuTimes cpu1 = cpu_times();
  const double steal_pct = cpu1.total > cpu0.total ? 100.0 * (cpu1.steal - cpu0.steal) / (cpu1.total - cpu0.total) : 0;
  const std::size_t n = latencies_ms.size();
  const double p50 = percentile(latencies_ms, 0.50), p90 = percentile(latencies_ms, 0.90), p99 = percentile(latencies_ms, 0.99);
  const double max = n ? *std::max_element(latencies_ms.begin(), latencies_ms.end()) : 0;
  // Memory over the run: after the first tenth (warm-up: allocator pools,
  // thread stacks), the last sample against the first and the peak.
  long rss_first = -1, rss_last = -1, rss_peak = -1;
  for (const auto& [t, kib] : rss) {
    if (t < elapsed * 0.1 && rss.size() > 10) continue;
    if (rss_first < 0) rss_first = kib;
    rss_last = kib;
    rss_peak = std::max(rss_peak, kib);
  }
  if (o.json) {
    std::cout << nlohmann::json{{"flow", o.flow}, {"connections", o.connections}, {"seconds", elapsed}, {"jobs", n},
                                {"errors", errors.load()}, {"jobs_per_second", static_cast<double>(n) / elapsed},
                                {"p50_ms", p50}, {"p90_ms", p90}, {"p99_ms", p99}, {"max_ms", max},
                                {"steal_percent", steal_pct}, {"rss_kib_after_warmup", rss_first}, {"rss_kib_end", rss_last}, {"rss_kib_peak", rss_peak}}
                     .dump()
              << "\n";
  } else {
    std::printf("%s, %d connections, %.0f s: %zu jobs, %ld errors, %.0f jobs/s; latency p50 %.1f ms, p90 %.1f ms, p99 %.1f ms, "
                "max %.1f ms; CPU steal %.0f%%\n",
                o.flow.c_str(), o.connections, elapsed, n, errors.load(), static_cast<double>(n) / elapsed, p50, p90, p99, max,
                steal_pct);
    if (o.server_pid)
      std::printf("server RSS: %.1f MiB after warm-up, %.1f MiB at the end, %.1f MiB peak\n", rss_first / 1024.0, rss_last / 1024.0,
                  rss_peak / 1024.0);
  }
  return errors.load() == 0 ? 0 : 1;
}
