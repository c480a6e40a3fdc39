// Tenants against real `voxd serve` processes: one server, and two replicas
// of one real redis-server. A tenant never sees, streams, downloads,
// analyses, cancels or deletes another's jobs (each answered exactly as an
// unknown id is); identical uploads by two tenants both run; its quotas
// answer 429 with Retry-After and recover; names and tags filter its list;
// the key file is read again without a restart; keys are never logged.
#include <signal.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "support/http_fixture.h"
#include "support/key_digest.h"
#include "support/redis_process.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

constexpr const char* kAcmeKey = "acme-secret-key-0001";
constexpr const char* kGlobexKey = "globex-secret-key-0002";
constexpr const char* kOpsKey = "ops-admin-key-0003";
constexpr const char* kSmallKey = "small-quota-key-0004";
constexpr const char* kChattyKey = "chatty-rate-key-0005";
constexpr const char* kDiskKey = "disk-quota-key-0006";
constexpr const char* kLateKey = "late-tenant-key-0007";
constexpr const char* kQueueKey = "queue-quota-key-0008";


json tenant(const std::string& name, const std::string& key, json quotas = json::object(), bool admin = false) {
  return {{"name", name}, {"keys", {key_entry(key)}}, {"quotas", quotas}, {"admin", admin}};
}

json tenant_table() {
  return {{"tenants",
           {tenant("acme", kAcmeKey), tenant("globex", kGlobexKey), tenant("ops", kOpsKey, json::object(), true),
            tenant("small", kSmallKey, {{"concurrent_jobs", 1}}),
            tenant("chatty", kChattyKey, {{"requests_per_minute", 60}}),
            tenant("disk", kDiskKey, {{"stored_bytes", 1}}), tenant("queue", kQueueKey, {{"queued_jobs", 1}})}}};
}

std::unique_ptr<httplib::Client> as(int port, const std::string& key) {
  auto c = make_client(port);
  if (!key.empty()) c->set_bearer_token_auth(key);
  return c;
}

std::vector<std::uint8_t> part() { return to_binary_stl(make_box({0, 0, 0}, {10, 8, 6})); }
// A job that runs for seconds: a hollow box on a fine grid with its wall thickness.
std::vector<std::uint8_t> hollow_box() {
  return to_binary_stl(concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10}))}));
}
constexpr const char* kSlowParams = R"({"grid": {"resolution": 360}, "analyses": [{"kind": "analysis", "min_wall": 1}]})";

// multipart with the job's name and tags beside mesh and params.
httplib::Result submit_labelled(httplib::Client& c, const std::vector<std::uint8_t>& mesh, const std::string& params,
                                const std::string& name, const std::string& tags) {
  httplib::MultipartFormDataItems items = {{"mesh", std::string(mesh.begin(), mesh.end()), "part.stl", "application/octet-stream"},
                                           {"params", params, "", "application/json"}};
  if (!name.empty()) items.push_back({"name", name, "", "text/plain"});
  if (!tags.empty()) items.push_back({"tags", tags, "", "application/json"});
  return c.Post("/v1/jobs", items);
}

class TenantsTest : public HttpServiceTest {
 protected:
  std::string write_tenants(const json& table) {
    const std::string path = dir_ + "/tenants.json";
    std::ofstream(path + ".tmp") << table.dump(2);
    std::filesystem::rename(path + ".tmp", path);
    return path;
  }

  json ok_json(const httplib::Result& res, int status, const std::string& component = "JobStatus") {
    return expect_json(res, status, component);
  }

  // One tenant's job as another sees it on every route: the same answer as
  // for an id that never existed (only the id in the message differs).
  void expect_hidden(httplib::Client& other, const std::string& id) {
    const std::string never = "0123456789abcdef0123456789abcdef";
    const std::vector<std::pair<std::string, std::string>> routes = {
        {"GET", ""}, {"GET", "/volume"}, {"GET", "/volume?format=nrrd"}, {"GET", "/events"},
        {"GET", "/analysis"}, {"GET", "/preview"}, {"GET", "/radiography?axis=z"}, {"GET", "/section?axis=z&index=3"},
        {"DELETE", ""}};
    for (const auto& [method, suffix] : routes) {
      auto ask = [&](const std::string& job) {
        const std::string path = "/v1/jobs/" + job + suffix;
        return method == "GET" ? other.Get(path.c_str()) : other.Delete(path.c_str());
      };
      const auto theirs = ask(id);
      const auto unknown = ask(never);
      ASSERT_TRUE(theirs && unknown) << method << " " << suffix;
      EXPECT_EQ(theirs->status, 404) << method << " " << suffix << ": " << theirs->body;
      json a = expect_problem(theirs, 404, "not-found"), b = expect_problem(unknown, 404, "not-found");
      std::string da = a.at("detail"), db = b.at("detail");
      da.replace(da.find(id), id.size(), never);
      EXPECT_EQ(da, db) << method << " " << suffix;
      EXPECT_EQ(a.at("title"), b.at("title"));
    }
  }

  json list(httplib::Client& c, const std::string& query = "") {
    return ok_json(c.Get(("/v1/jobs" + query).c_str()), 200, "JobList");
  }
  static std::vector<std::string> ids(const json& page) {
    std::vector<std::string> out;
    for (const json& j : page.at("jobs")) out.push_back(j.at("id"));
    return out;
  }

  // Two tenants on ports `pa` and `pb` (the same server, or two replicas).
  // `resolution` makes each call's jobs its own; each call leaves nothing behind.
  void expect_isolated(int pa, int pb, int resolution) {
    auto acme = as(pa, kAcmeKey), globex = as(pb, kGlobexKey), ops = as(pa, kOpsKey), globex_here = as(pa, kGlobexKey);
    const std::string params = R"({"grid": {"resolution": )" + std::to_string(resolution) + "}}";
    const json a = ok_json(submit_labelled(*acme, part(), params, "bracket-a", R"({"project": "pump", "rev": "b"})"), 202);
    const json b = ok_json(post_multipart(*globex, "/v1/jobs", part(), "globex part.stl", params), 202);
    const std::string ia = a.at("id"), ib = b.at("id");
    EXPECT_EQ(wait_for_job(*acme, ia).at("state"), "succeeded");
    const json done_b = wait_for_job(*globex, ib);
    EXPECT_EQ(done_b.at("state"), "succeeded");
    // Identical uploads: both ran, neither answered from the other's.
    EXPECT_FALSE(done_b.at("cached").get<bool>());
    EXPECT_NE(done_b.at("content_hash"), a.at("content_hash"));
    EXPECT_EQ(a.at("name"), "bracket-a");
    EXPECT_EQ(a.at("tags"), json({{"project", "pump"}, {"rev", "b"}}));
    EXPECT_EQ(a.at("tenant"), "acme");
    EXPECT_EQ(done_b.at("name"), "globex part.stl") << "the default name is the uploaded file's";

    expect_hidden(*globex, ia);
    expect_hidden(*globex_here, ia);
    expect_hidden(*acme, ib);
    // Still there for its owner after the other's DELETE, with the same bytes.
    const json still = ok_json(acme->Get(("/v1/jobs/" + ia).c_str()), 200);
    EXPECT_EQ(still.at("state"), "succeeded");
    const auto va = acme->Get(("/v1/jobs/" + ia + "/volume").c_str());
    const auto vb = globex->Get(("/v1/jobs/" + ib + "/volume").c_str());
    ASSERT_TRUE(va && vb);
    EXPECT_EQ(va->status, 200);
    EXPECT_EQ(va->body, vb->body);

    // Lists: each its own; the admin every tenant's.
    EXPECT_EQ(ids(list(*acme)), std::vector<std::string>{ia});
    EXPECT_EQ(list(*acme).at("total"), 1);
    EXPECT_EQ(ids(list(*globex)), std::vector<std::string>{ib});
    const std::vector<std::string> all = ids(list(*ops));
    EXPECT_NE(std::find(all.begin(), all.end(), ia), all.end());
    EXPECT_NE(std::find(all.begin(), all.end(), ib), all.end());
    // The admin reaches any job.
    EXPECT_EQ(ok_json(ops->Get(("/v1/jobs/" + ib).c_str()), 200).at("id"), ib);

    // The same tenant's identical upload is answered from its own result.
    const json again = ok_json(post_multipart(*acme, "/v1/jobs", part(), "part.stl", params), 202);
    EXPECT_TRUE(again.at("cached").get<bool>());
    EXPECT_EQ(again.at("content_hash"), a.at("content_hash"));

    // Names and tags filter the tenant's own list only.
    EXPECT_EQ(ids(list(*acme, "?name=bracket-a")), std::vector<std::string>{ia});
    EXPECT_EQ(ids(list(*acme, "?tag=project:pump&tag=rev:b")), std::vector<std::string>{ia});
    EXPECT_EQ(list(*acme, "?tag=project:pump&tag=rev:c").at("total"), 0);
    EXPECT_EQ(list(*globex, "?name=bracket-a").at("total"), 0);
    EXPECT_EQ(list(*acme, "?name=part.stl").at("total"), 1);
    expect_problem(acme->Get("/v1/jobs?tag=nocolon"), 400, "invalid-query");
    expect_problem(submit_labelled(*acme, part(), params, "", R"(["not", "an", "object"])"), 422, "invalid-params");

    // The owner deletes; the other's identical job stays.
    EXPECT_EQ(acme->Delete(("/v1/jobs/" + ia).c_str())->status, 204);
    expect_problem(acme->Get(("/v1/jobs/" + ia).c_str()), 404, "not-found");
    EXPECT_EQ(ok_json(globex->Get(("/v1/jobs/" + ib).c_str()), 200).at("state"), "succeeded");
    EXPECT_EQ(acme->Delete(("/v1/jobs/" + again.at("id").get<std::string>()).c_str())->status, 204);
    EXPECT_EQ(globex->Delete(("/v1/jobs/" + ib).c_str())->status, 204);
  }

  // Quotas on ports `pa` and `pb`: each refusal is a 429 quota-exceeded
  // with Retry-After, and goes away once the tenant holds less.
  void expect_quotas(int pa, int pb) {
    // concurrent_jobs 1: a second job while the first runs.
    auto small = as(pa, kSmallKey), small_b = as(pb, kSmallKey);
    const std::string slow = ok_json(post_multipart(*small, "/v1/jobs", hollow_box(), "box.stl", kSlowParams), 202).at("id");
    const auto refused = post_multipart(*small_b, "/v1/jobs", part(), "part.stl", "{}");
    const json p = expect_problem(refused, 429, "quota-exceeded");
    EXPECT_NE(p.at("detail").get<std::string>().find("concurrent"), std::string::npos) << p.dump();
    EXPECT_FALSE(refused->get_header_value("Retry-After").empty());
    const std::string state = ok_json(small->Get(("/v1/jobs/" + slow).c_str()), 200).at("state");
    EXPECT_TRUE(state == "queued" || state == "running") << state << ": make the slow job slower";
    // Another tenant is not held back by it.
    auto acme = as(pb, kAcmeKey);
    ok_json(post_multipart(*acme, "/v1/jobs", part(), "part.stl", R"({"grid": {"resolution": 20}})"), 202);
    ASSERT_EQ(small->Delete(("/v1/jobs/" + slow).c_str())->status, 202);
    EXPECT_EQ(wait_for_job(*small, slow, 60).at("state"), "cancelled");
    const std::string next = ok_json(post_multipart(*small_b, "/v1/jobs", part(), "part.stl", "{}"), 202).at("id");
    EXPECT_EQ(wait_for_job(*small_b, next).at("state"), "succeeded");

    // stored_bytes 1: nothing more once a result is kept, until it is deleted.
    auto disk = as(pa, kDiskKey), disk_b = as(pb, kDiskKey);
    const json kept = ok_json(post_multipart(*disk, "/v1/jobs", part(), "part.stl", "{}"), 202);
    const json kept_done = wait_for_job(*disk, kept.at("id"));
    EXPECT_GT(kept_done.at("stored_bytes").get<std::uint64_t>(), 0u);
    const auto full = post_multipart(*disk_b, "/v1/jobs", part(), "part.stl", R"({"grid": {"resolution": 20}})");
    EXPECT_NE(expect_problem(full, 429, "quota-exceeded").at("detail").get<std::string>().find("DELETE"), std::string::npos);
    EXPECT_EQ(full->get_header_value("Retry-After"), "60");
    EXPECT_EQ(disk->Delete(("/v1/jobs/" + kept.at("id").get<std::string>()).c_str())->status, 204);
    ok_json(post_multipart(*disk_b, "/v1/jobs", part(), "part.stl", R"({"grid": {"resolution": 20}})"), 202);

    // requests_per_minute 60, per replica: a burst of 60, then a second's wait.
    auto chatty = as(pa, kChattyKey);
    int refused_at = -1;
    for (int i = 0; i < 70 && refused_at < 0; ++i) {
      const auto r = chatty->Get("/v1/jobs");
      ASSERT_TRUE(r);
      if (r->status == 429) {
        refused_at = i;
        expect_problem(r, 429, "quota-exceeded");
        EXPECT_EQ(r->get_header_value("Retry-After"), "1");
      }
    }
    // A minute's worth, plus what refills (1/s) while the burst is sent.
    EXPECT_GE(refused_at, 60) << "the bucket holds a minute's worth";
    EXPECT_LE(refused_at, 65);
    EXPECT_EQ(as(pa, kAcmeKey)->Get("/v1/jobs")->status, 200) << "another tenant's rate is its own";
    std::this_thread::sleep_for(1100ms);
    EXPECT_EQ(chatty->Get("/v1/jobs")->status, 200);
  }
};

TEST_F(TenantsTest, TwoTenantsOnOneServerNeverSeeEachOthersJobs) {
  start({"--tenants", write_tenants(tenant_table())});
  expect_isolated(server_->port(), server_->port(), 32);
}

TEST_F(TenantsTest, TwoTenantsOnTwoReplicasOfOneRedisNeverSeeEachOthersJobs) {
  RedisProcess redis(dir_ + "/redis");
  const std::string file = write_tenants(tenant_table());
  ServerProcess r0(dir_ + "/r0", {"--redis", redis.url(), "--tenants", file, "--workers", "2"});
  ServerProcess r1(dir_ + "/r1", {"--redis", redis.url(), "--tenants", file, "--workers", "2"});
  expect_isolated(r0.port(), r1.port(), 32);
  expect_isolated(r1.port(), r0.port(), 33);
  EXPECT_EQ(r0.stop(), 0) << r0.log();
  EXPECT_EQ(r1.stop(), 0) << r1.log();
}

TEST_F(TenantsTest, QuotasAnswer429WithRetryAfterAndRecoverOnOneServer) {
  start({"--tenants", write_tenants(tenant_table())});
  expect_quotas(server_->port(), server_->port());
  // Counted by tenant and quota, under configured names only.
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find(R"(voxd_tenant_quota_rejections_total{tenant="small",quota="concurrent_jobs"} 1)"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find(R"(voxd_tenant_quota_rejections_total{tenant="disk",quota="stored_bytes"} 1)"), std::string::npos);
  EXPECT_NE(metrics.find(R"(voxd_tenant_quota_rejections_total{tenant="chatty",quota="requests_per_minute"} 1)"), std::string::npos);
  EXPECT_NE(metrics.find(R"(voxd_tenant_jobs_submitted_total{tenant="small"} 2)"), std::string::npos);
  EXPECT_NE(metrics.find(R"(voxd_tenant_requests_total{tenant="chatty"})"), std::string::npos);
}

// queued_jobs: with one worker kept busy by another tenant, one job of this
// tenant may wait; a second is refused until the first has started.
TEST_F(TenantsTest, TheQueuedJobsQuotaCountsOnlyJobsWaitingForAWorker) {
  start({"--tenants", write_tenants(tenant_table()), "--workers", "1"});
  auto acme = as(server_->port(), kAcmeKey), queue = as(server_->port(), kQueueKey);
  const std::string busy = ok_json(post_multipart(*acme, "/v1/jobs", hollow_box(), "box.stl", kSlowParams), 202).at("id");
  wait_for_state(*acme, busy, "running");
  const std::string waiting = ok_json(post_multipart(*queue, "/v1/jobs", part(), "part.stl", "{}"), 202).at("id");
  const auto refused = post_multipart(*queue, "/v1/jobs", part(), "part.stl", R"({"grid": {"resolution": 20}})");
  const json p = expect_problem(refused, 429, "quota-exceeded");
  EXPECT_NE(p.at("detail").get<std::string>().find("waiting"), std::string::npos) << p.dump();
  EXPECT_EQ(refused->get_header_value("Retry-After"), "5");
  ASSERT_EQ(acme->Delete(("/v1/jobs/" + busy).c_str())->status, 202);
  EXPECT_EQ(wait_for_job(*queue, waiting).at("state"), "succeeded");
  ok_json(post_multipart(*queue, "/v1/jobs", part(), "part.stl", R"({"grid": {"resolution": 20}})"), 202);
}

TEST_F(TenantsTest, QuotasAnswer429AndRecoverAcrossTwoReplicasOfOneRedis) {
  RedisProcess redis(dir_ + "/redis");
  const std::string file = write_tenants(tenant_table());
  ServerProcess r0(dir_ + "/r0", {"--redis", redis.url(), "--tenants", file, "--workers", "2"});
  ServerProcess r1(dir_ + "/r1", {"--redis", redis.url(), "--tenants", file, "--workers", "2"});
  expect_quotas(r0.port(), r1.port());
  EXPECT_EQ(r0.stop(), 0) << r0.log();
  EXPECT_EQ(r1.stop(), 0) << r1.log();
}

TEST_F(TenantsTest, KeysAreCheckedReloadedWithoutARestartAndNeverLogged) {
  const std::string file = write_tenants(tenant_table());
  start({"--tenants", file, "--log-format", "json"});
  expect_problem(http().Get("/v1/jobs"), 401, "unauthorized");
  expect_problem(as(server_->port(), "not-a-key")->Get("/v1/jobs"), 401, "unauthorized");
  // The scheme is case-insensitive; the key is not.
  httplib::Headers lower = {{"Authorization", std::string("bearer ") + kAcmeKey}};
  EXPECT_EQ(http().Get("/v1/jobs", lower)->status, 200);
  EXPECT_EQ(as(server_->port(), "ACME-SECRET-KEY-0001")->Get("/v1/jobs")->status, 401);
  // Probes and the page need no key.
  EXPECT_EQ(http().Get("/healthz")->status, 200);

  // A tenant added to the file works within a few seconds, no restart.
  json table = tenant_table();
  table["tenants"].push_back(tenant("late", kLateKey));
  write_tenants(table);
  auto late = as(server_->port(), kLateKey);
  int status = 0;
  for (int i = 0; i < 60 && status != 200; ++i) {
    status = late->Get("/v1/jobs")->status;
    if (status != 200) std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(status, 200);
  // A removed one stops working, on SIGHUP at once.
  table["tenants"].erase(table["tenants"].begin());  // acme
  write_tenants(table);
  ::kill(server_->pid(), SIGHUP);
  status = 200;
  for (int i = 0; i < 60 && status == 200; ++i) {
    status = as(server_->port(), kAcmeKey)->Get("/v1/jobs")->status;
    if (status == 200) std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(status, 401);
  // A file that no longer parses keeps the last good table, and says why.
  std::ofstream(file) << "{\"tenants\": [{\"name\": \"x\", \"keys\": [\"" << kAcmeKey << "\"]}]}";
  ::kill(server_->pid(), SIGHUP);
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(late->Get("/v1/jobs")->status, 200);
  EXPECT_EQ(as(server_->port(), kAcmeKey)->Get("/v1/jobs")->status, 401);

  const std::string log = server_->log();
  EXPECT_NE(log.find("kept the last good table"), std::string::npos) << log;
  // Every line is JSON, the warnings from the tenants' reload too.
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) {
      EXPECT_TRUE(json::accept(line)) << line;
    }
  for (const char* key : {kAcmeKey, kGlobexKey, kLateKey, "not-a-key"}) EXPECT_EQ(log.find(key), std::string::npos) << key;
  const std::string metrics = http().Get("/metrics")->body;
  EXPECT_NE(metrics.find(R"(voxd_tenant_requests_total{tenant="late"})"), std::string::npos);
  for (const char* key : {kAcmeKey, kLateKey, "not-a-key"}) EXPECT_EQ(metrics.find(key), std::string::npos) << key;
}

TEST_F(TenantsTest, AFileWithPlainKeysOrUnknownFieldsDoesNotStartTheService) {
  const std::string path = dir_ + "/bad.json";
  std::ofstream(path) << R"({"tenants": [{"name": "acme", "keys": ["plain-key-not-hashed"]}]})";
  const ProcessResult r = run_process(serve_binary() + " serve --port 0 --data-dir " + dir_ + "/d --tenants " + path);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("sha256sum"), std::string::npos) << r.err;
  EXPECT_EQ((r.out + r.err).find("plain-key-not-hashed"), std::string::npos) << "a key is never echoed";
  std::ofstream(path) << R"({"tenants": [], "webhook_hostz": []})";
  const ProcessResult r2 = run_process(serve_binary() + " serve --port 0 --data-dir " + dir_ + "/d --tenants " + path);
  EXPECT_NE(r2.exit_code, 0);
  EXPECT_NE(r2.err.find("webhook_hostz"), std::string::npos) << r2.err;
}

// Without a tenants file nothing changes: no key, or --api-keys holders,
// see every job as before tenants existed.
TEST_F(TenantsTest, WithoutATenantsFileEveryKeyHolderSeesEveryJobAsBefore) {
  start({"--api-keys", "k1,k2"});
  auto one = as(server_->port(), "k1"), two = as(server_->port(), "k2");
  const json a = ok_json(post_multipart(*one, "/v1/jobs", part(), "part.stl", "{}"), 202);
  wait_for_job(*one, a.at("id"));
  EXPECT_EQ(ok_json(two->Get(("/v1/jobs/" + a.at("id").get<std::string>()).c_str()), 200).at("tenant"), nullptr);
  EXPECT_EQ(list(*two).at("total"), 1);
  const json again = ok_json(post_multipart(*two, "/v1/jobs", part(), "part.stl", "{}"), 202);
  EXPECT_TRUE(again.at("cached").get<bool>());
  // Labels are short: a long name is refused naming its field; a huge part as it arrives.
  const json p = expect_problem(submit_labelled(*one, part(), "{}", std::string(300, 'n'), ""), 422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/name");
  expect_problem(submit_labelled(*one, part(), "{}", std::string(70000, 'n'), ""), 413, "params-too-large");
  expect_problem(submit_labelled(*one, part(), "{}", "", R"({"bad key": "x"})"), 422, "invalid-params");
  EXPECT_EQ(http().Get("/healthz")->status, 200);
}

}  // namespace
}  // namespace voxd::test
