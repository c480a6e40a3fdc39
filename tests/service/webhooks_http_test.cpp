// Webhooks against real `voxd serve` processes and a receiver on loopback:
// exactly one callback per finished job (one more only for each attempt the
// receiver failed), its HMAC-SHA256 signature checked by an independent
// implementation (Python's hmac, as docs/security.md shows a receiver), its
// body the job's final status; none to a host outside the allow-list; a
// delivery survives a restart of the service; replicas of one Redis deliver
// each job's once.
#include <atomic>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>

#include "support/http_fixture.h"
#include "support/key_digest.h"
#include "support/redis_process.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

constexpr const char* kSecret = "whsec-0123456789abcdef";
constexpr const char* kKey = "acme-webhook-key-01";


struct Callback {
  httplib::Headers headers;
  std::string target, body;
};

// A loopback receiver that records every callback; it answers 500 to the
// first `fail_first` of them.
class Receiver {
 public:
  explicit Receiver(int fail_first = 0, int port = 0) : fail_first_(fail_first) {
    server_.Post(".*", [this](const httplib::Request& req, httplib::Response& res) {
      std::lock_guard lock(mutex_);
      got_.push_back({req.headers, req.target, req.body});
      res.status = static_cast<int>(got_.size()) <= fail_first_ ? 500 : 204;
    });
    port_ = port == 0 ? server_.bind_to_any_port("127.0.0.1") : (server_.bind_to_port("127.0.0.1", port) ? port : -1);
    if (port_ <= 0) throw std::runtime_error("the receiver cannot listen");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
    for (int i = 0; i < 200 && !server_.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ~Receiver() {
    server_.stop();
    thread_.join();
  }
  int port() const { return port_; }
  std::vector<Callback> got() {
    std::lock_guard lock(mutex_);
    return got_;
  }
  // Waits until `n` callbacks came (or `seconds` passed).
  std::vector<Callback> wait_for(std::size_t n, int seconds = 30) {
    for (int i = 0; i < seconds * 20 && got().size() < n; ++i) std::this_thread::sleep_for(50ms);
    return got();
  }

 private:
  httplib::Server server_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Callback> got_;
  int fail_first_;
  int port_ = 0;
};

std::string header(const Callback& c, const std::string& name) {
  auto it = c.headers.find(name);
  return it == c.headers.end() ? std::string() : it->second;
}

// The signature's check as a receiver in Python makes it (docs/security.md).
void expect_signed(const Callback& c, const std::string& dir) {
  const std::string sig = header(c, "X-Voxd-Signature");
  ASSERT_EQ(sig.rfind("t=", 0), 0u) << sig;
  const std::size_t comma = sig.find(",v1=");
  ASSERT_NE(comma, std::string::npos) << sig;
  const std::string t = sig.substr(2, comma - 2), v1 = sig.substr(comma + 4);
  const long long age = std::time(nullptr) - std::stoll(t);
  EXPECT_LE(std::llabs(age), 60) << "t is the time of sending";
  std::ofstream(dir + "/body.bin", std::ios::binary) << c.body;
  const ProcessResult r = run_process(
      "python3 -c \"import hmac,hashlib,sys; b=open(sys.argv[1],'rb').read(); "
      "print(hmac.new(sys.argv[2].encode(), sys.argv[3].encode()+b'.'+b, hashlib.sha256).hexdigest())\" " +
      dir + "/body.bin '" + kSecret + "' " + t);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.substr(0, 64), v1) << "the signature does not verify";
  EXPECT_EQ(header(c, "Content-Type"), "application/json");
  EXPECT_EQ(header(c, "X-Voxd-Event"), "job.finished");
}

class WebhooksTest : public HttpServiceTest {
 protected:
  std::string tenants(const std::vector<int>& ports) {
    json hosts = json::array();
    for (int p : ports) hosts.push_back("127.0.0.1:" + std::to_string(p));
    const json table = {{"tenants", {{{"name", "acme"}, {"keys", {key_entry(kKey)}}, {"webhook_secret", kSecret}},
                                     {{"name", "nosecret"}, {"keys", {key_entry("nosecret-key-000")}}}}},
                        {"webhook_hosts", hosts}};
    const std::string path = dir_ + "/tenants.json";
    std::ofstream(path) << table.dump();
    return path;
  }
  std::unique_ptr<httplib::Client> acme(int port) {
    auto c = make_client(port);
    c->set_bearer_token_auth(kKey);
    return c;
  }
  httplib::Result submit_with_callback(httplib::Client& c, const std::string& callback, const std::string& params = "{}") {
    httplib::MultipartFormDataItems items = {
        {"mesh", text_of(to_binary_stl(make_box({0, 0, 0}, {10, 8, 6}))), "part.stl", "application/octet-stream"},
        {"params", params, "", "application/json"},
        {"callback", callback, "", "text/plain"}};
    return c.Post("/v1/jobs", items);
  }
};

TEST_F(WebhooksTest, EachFinishedJobIsCalledBackOnceSignedWithItsFinalStatus) {
  Receiver receiver;
  start({"--tenants", tenants({receiver.port()})});
  auto c = acme(server_->port());
  const std::string url = "http://127.0.0.1:" + std::to_string(receiver.port()) + "/hooks/voxd?source=test";
  std::vector<std::string> ids;
  for (int res : {20, 24, 28})
    ids.push_back(expect_json(submit_with_callback(*c, url, R"({"grid": {"resolution": )" + std::to_string(res) + "}}"), 202,
                              "JobStatus")
                      .at("id"));
  for (const std::string& id : ids) wait_for_job(*c, id);
  const std::vector<Callback> got = receiver.wait_for(3);
  std::this_thread::sleep_for(1500ms);  // and no more come
  ASSERT_EQ(receiver.got().size(), 3u);
  std::set<std::string> delivered;
  for (const Callback& cb : got) {
    expect_signed(cb, dir_);
    EXPECT_EQ(cb.target, "/hooks/voxd?source=test");
    const std::string id = header(cb, "X-Voxd-Delivery");
    delivered.insert(id);
    const json body = json::parse(cb.body);
    EXPECT_EQ(body.at("id"), id);
    EXPECT_EQ(body.at("state"), "succeeded");
    EXPECT_EQ(body.at("callback"), url);
    // The final status, as the API answers it.
    EXPECT_EQ(body, json::parse(c->Get(("/v1/jobs/" + id).c_str())->body));
    schemas_->add("JobStatus", cb.body);
  }
  EXPECT_EQ(delivered, std::set<std::string>(ids.begin(), ids.end()));
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find(R"(voxd_webhook_deliveries_total{outcome="delivered"} 3)"), std::string::npos) << metrics;
}

TEST_F(WebhooksTest, AFailingReceiverIsRetriedWithTheSameDeliveryUntilItAnswers) {
  Receiver receiver(/*fail_first=*/2);
  start({"--tenants", tenants({receiver.port()})});
  auto c = acme(server_->port());
  const std::string id =
      expect_json(submit_with_callback(*c, "http://127.0.0.1:" + std::to_string(receiver.port()) + "/"), 202, "JobStatus").at("id");
  wait_for_job(*c, id);
  // Two failures (500), retried after 1 s and 2 s, then delivered: three in all.
  const std::vector<Callback> got = receiver.wait_for(3, 20);
  std::this_thread::sleep_for(2500ms);
  ASSERT_EQ(receiver.got().size(), 3u);
  for (const Callback& cb : got) {
    expect_signed(cb, dir_);
    EXPECT_EQ(header(cb, "X-Voxd-Delivery"), id) << "a retry is the same delivery";
    EXPECT_EQ(cb.body, got.front().body);
  }
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find(R"(voxd_webhook_deliveries_total{outcome="retried"} 2)"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find(R"(voxd_webhook_deliveries_total{outcome="delivered"} 1)"), std::string::npos);
}

TEST_F(WebhooksTest, NoCallbackGoesToAHostOutsideTheAllowList) {
  Receiver allowed, outside;
  start({"--tenants", tenants({allowed.port()})});
  auto c = acme(server_->port());
  const std::string out = std::to_string(outside.port());
  for (const std::string& url :
       {"http://127.0.0.1:" + out + "/", "http://localhost:" + std::to_string(allowed.port()) + "/",
        "http://127.0.0.1:" + std::to_string(allowed.port()) + "@127.0.0.1:" + out + "/", "ftp://127.0.0.1:" + out + "/",
        "http://[::1]:" + out + "/", "http://127.0.0.1:" + std::to_string(allowed.port()) + "/#frag", std::string("not a url")}) {
    const json p = expect_problem(submit_with_callback(*c, url), 422, "invalid-params");
    ASSERT_EQ(p.at("errors").size(), 1u) << url;
    EXPECT_EQ(p.at("errors").at(0).at("path"), "/callback") << url;
  }
  // A tenant without a webhook secret cannot name one, even an allowed host.
  auto nosecret = make_client(server_->port());
  nosecret->set_bearer_token_auth("nosecret-key-000");
  const json p = expect_problem(submit_with_callback(*nosecret, "http://127.0.0.1:" + std::to_string(allowed.port()) + "/"), 422,
                                "invalid-params");
  EXPECT_NE(p.at("errors").at(0).at("message").get<std::string>().find("secret"), std::string::npos);
  // A job without a callback calls nobody.
  const std::string id = expect_json(post_multipart(*c, "/v1/jobs", to_binary_stl(make_box({0, 0, 0}, {4, 4, 4})), "a.stl", "{}"),
                                     202, "JobStatus")
                             .at("id");
  wait_for_job(*c, id);
  std::this_thread::sleep_for(1500ms);
  EXPECT_TRUE(outside.got().empty());
  EXPECT_TRUE(allowed.got().empty());
}

TEST_F(WebhooksTest, ADeliveryPendingWhenTheServiceStopsIsMadeAfterItsRestart) {
  int port = 0;
  {
    Receiver probe;  // a free port, then closed: nobody answers there yet
    port = probe.port();
  }
  const std::string file = tenants({port});
  start({"--tenants", file});
  auto c = acme(server_->port());
  const std::string id =
      expect_json(submit_with_callback(*c, "http://127.0.0.1:" + std::to_string(port) + "/late"), 202, "JobStatus").at("id");
  wait_for_job(*c, id);
  std::this_thread::sleep_for(1500ms);  // a first attempt or two fail: refused
  ASSERT_EQ(server_->stop(), 0);
  Receiver receiver(0, port);
  start({"--tenants", file});
  const std::vector<Callback> got = receiver.wait_for(1, 20);
  std::this_thread::sleep_for(1500ms);
  ASSERT_EQ(receiver.got().size(), 1u);
  expect_signed(got.front(), dir_);
  EXPECT_EQ(header(got.front(), "X-Voxd-Delivery"), id);
}

TEST_F(WebhooksTest, ReplicasOfOneRedisCallEachJobBackOnce) {
  Receiver receiver;
  RedisProcess redis(dir_ + "/redis");
  const std::string file = tenants({receiver.port()});
  ServerProcess r0(dir_ + "/r0", {"--redis", redis.url(), "--tenants", file, "--workers", "1"});
  ServerProcess r1(dir_ + "/r1", {"--redis", redis.url(), "--tenants", file, "--workers", "1"});
  auto c0 = acme(r0.port()), c1 = acme(r1.port());
  const std::string url = "http://127.0.0.1:" + std::to_string(receiver.port()) + "/";
  std::vector<std::string> ids;
  for (int i = 0; i < 6; ++i)
    ids.push_back(expect_json(submit_with_callback(i % 2 ? *c1 : *c0, url, R"({"grid": {"resolution": )" + std::to_string(20 + i) + "}}"),
                              202, "JobStatus")
                      .at("id"));
  for (const std::string& id : ids) EXPECT_EQ(wait_for_job(*c0, id).at("state"), "succeeded");
  receiver.wait_for(6);
  std::this_thread::sleep_for(2000ms);
  const std::vector<Callback> got = receiver.got();
  ASSERT_EQ(got.size(), 6u);
  std::set<std::string> delivered;
  for (const Callback& cb : got) {
    expect_signed(cb, dir_);
    delivered.insert(header(cb, "X-Voxd-Delivery"));
  }
  EXPECT_EQ(delivered, std::set<std::string>(ids.begin(), ids.end()));
  EXPECT_EQ(r0.stop(), 0) << r0.log();
  EXPECT_EQ(r1.stop(), 0) << r1.log();
}

}  // namespace
}  // namespace voxd::test
