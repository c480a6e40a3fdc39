// The parts of tenants and webhooks that take outside text, in process: the
// key file's checks, callback URLs, the request-rate bucket, and the
// signature (against RFC 4231's HMAC-SHA256 test vectors).
#include <gtest/gtest.h>

#include "server/tenants/request_rate.h"
#include "server/tenants/tenant_directory.h"
#include "server/webhooks/webhook_signature.h"
#include "server/webhooks/webhook_url.h"

namespace voxd::server {
namespace {

using namespace std::chrono_literals;

const std::string kDigest = "sha256:" + std::string(64, 'a');

std::string refusal(const std::string& text) {
  try {
    parse_tenant_table(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(TenantTable, AGoodFileParsesWithItsQuotasAdminAndHosts) {
  const TenantTable t = parse_tenant_table(R"({"tenants": [
      {"name": "acme", "keys": [")" + kDigest + R"("], "quotas": {"concurrent_jobs": 2, "stored_bytes": 1000},
       "webhook_secret": "0123456789abcdef"},
      {"name": "ops.team_1", "keys": [], "admin": true}],
    "webhook_hosts": ["Hooks.Example.com", "127.0.0.1:9000"]})");
  ASSERT_EQ(t.tenants.size(), 2u);
  EXPECT_EQ(t.tenants[0].quotas.concurrent_jobs, 2u);
  EXPECT_EQ(t.tenants[0].quotas.queued_jobs, 0u);
  EXPECT_EQ(t.tenants[0].quotas.stored_bytes, 1000u);
  EXPECT_FALSE(t.tenants[0].admin);
  EXPECT_TRUE(t.tenants[1].admin);
  ASSERT_EQ(t.keys.size(), 1u);
  EXPECT_EQ(t.keys[0].first, std::string(64, 'a'));
  EXPECT_EQ(t.webhook_hosts, (std::vector<std::string>{"hooks.example.com", "127.0.0.1:9000"}));
}

TEST(TenantTable, EveryMistakeIsRefusedSayingWhatAndNeverQuotingAKey) {
  EXPECT_NE(refusal("not json").find("not JSON"), std::string::npos);
  // A number past a double (the fuzzer's first find: nlohmann throws out_of_range).
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": [], "quotas": {"stored_bytes": 1e400}}]})").find("not JSON"), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": {}})").find("array"), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [], "extra": 1})").find("\"extra\""), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a b", "keys": []}]})").find("name"), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": []}, {"name": "a", "keys": []}]})").find("twice"), std::string::npos);
  const std::string plain = refusal(R"({"tenants": [{"name": "a", "keys": ["my-plain-secret"]}]})");
  EXPECT_NE(plain.find("sha256sum"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("my-plain-secret"), std::string::npos) << plain;
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": ["sha256:)" + std::string(64, 'A') + R"("]}]})").find("lowercase"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": [")" + kDigest + R"("]}, {"name": "b", "keys": [")" + kDigest + R"("]}]})")
                .find("unique"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": [], "quotas": {"concurrent_jobs": -1}}]})").find("concurrent_jobs"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": [], "quotas": {"jobs": 1}}]})").find("\"jobs\""), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [{"name": "a", "keys": [], "webhook_secret": "short"}]})").find("16"), std::string::npos);
  EXPECT_NE(refusal(R"({"tenants": [], "webhook_hosts": ["http://x/"]})").find("host:port"), std::string::npos);
}

TEST(TenantDirectory, ApiKeysAreTheUnnamedTenantAndWebhookHostsMatchExactly) {
  TenantDirectory d("", {"k1", "k2"}, {"127.0.0.1:9000", "Hooks.Example.com"}, "0123456789abcdef");
  EXPECT_TRUE(d.needs_key());
  EXPECT_TRUE(d.unnamed_sees_all());
  ASSERT_TRUE(d.authenticate("k2"));
  EXPECT_EQ(d.authenticate("k2")->name, "");
  EXPECT_EQ(d.authenticate("k2")->webhook_secret, "0123456789abcdef");
  EXPECT_FALSE(d.authenticate("k3"));
  EXPECT_FALSE(d.authenticate("K1"));
  EXPECT_TRUE(d.webhook_host_allowed("127.0.0.1", 9000));
  EXPECT_FALSE(d.webhook_host_allowed("127.0.0.1", 9001));
  EXPECT_FALSE(d.webhook_host_allowed("localhost", 9000));
  EXPECT_TRUE(d.webhook_host_allowed("hooks.example.com", 443));
  EXPECT_TRUE(d.webhook_host_allowed("HOOKS.example.com", 80));
  EXPECT_FALSE(d.webhook_host_allowed("hooks.example.com", 8080)) << "a bare host allows the web's ports only";
  EXPECT_FALSE(d.webhook_host_allowed("evil.hooks.example.com", 443));
  TenantDirectory open("", {}, {}, "");
  EXPECT_FALSE(open.needs_key());
  EXPECT_TRUE(open.unnamed_sees_all());
  EXPECT_EQ(key_digest("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");  // FIPS 180-2
}

TEST(WebhookUrl, OnlyPlainHttpUrlsWithAHostParse) {
  std::string why;
  auto u = parse_webhook_url("https://Hooks.Example.com/a/b?c=d", &why);
  ASSERT_TRUE(u) << why;
  EXPECT_EQ(u->scheme, "https");
  EXPECT_EQ(u->host, "hooks.example.com");
  EXPECT_EQ(u->port, 443);
  EXPECT_EQ(u->target, "/a/b?c=d");
  u = parse_webhook_url("http://127.0.0.1:9000", &why);
  ASSERT_TRUE(u) << why;
  EXPECT_EQ(u->port, 9000);
  EXPECT_EQ(u->target, "/");
  u = parse_webhook_url("http://[::1]:8080/x", &why);
  ASSERT_TRUE(u) << why;
  EXPECT_EQ(u->host, "::1");
  EXPECT_EQ(u->port, 8080);
  u = parse_webhook_url("http://[::1]/x", &why);
  ASSERT_TRUE(u) << why;
  EXPECT_EQ(u->port, 80);
  u = parse_webhook_url("http://example.com?x=1", &why);
  ASSERT_TRUE(u) << why;
  EXPECT_EQ(u->target, "/?x=1");
  for (const char* bad : {"ftp://x/", "//x/", "http://", "http://:80/", "http://a@b/", "http://x:0/", "http://x:65536/",
                          "http://x:/", "http://x/#f", "http://x y/", "http://x/\r\nHost: y", "http://[::1/", "http://a/b\x01", "http://a/caf\xc3\xa9"})
    EXPECT_FALSE(parse_webhook_url(bad, &why)) << bad;
}

TEST(RequestRate, ABurstOfAMinutesWorthThenTheQuotasRate) {
  RequestRate rate;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 120; ++i) EXPECT_FALSE(rate.take("a", 120, t0)) << i;
  EXPECT_EQ(rate.take("a", 120, t0), 1);
  EXPECT_FALSE(rate.take("b", 120, t0)) << "each tenant has its own bucket";
  EXPECT_FALSE(rate.take("a", 120, t0 + 500ms)) << "two a second come back";
  EXPECT_TRUE(rate.take("a", 120, t0 + 500ms));
  EXPECT_EQ(rate.take("slow", 1, t0), std::nullopt);
  EXPECT_EQ(rate.take("slow", 1, t0), 60) << "one a minute: a minute to wait";
  EXPECT_FALSE(rate.take("free", 0, t0));
}

TEST(WebhookSignature, IsHmacSha256AsRfc4231AndSignsTheTimeWithTheBody) {
  // RFC 4231 test cases 2 and 6.
  EXPECT_EQ(hmac_sha256_hex("Jefe", "what do ya want for nothing?"),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  EXPECT_EQ(hmac_sha256_hex(std::string(131, '\xaa'), "Test Using Larger Than Block-Size Key - Hash Key First"),
            "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
  EXPECT_EQ(webhook_signature("Jefe", 1700000000, "{}"), "t=1700000000,v1=" + hmac_sha256_hex("Jefe", "1700000000.{}"));
}

}  // namespace
}  // namespace voxd::server
