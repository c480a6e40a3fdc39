// A job's states are named once (kJobStateNames); the records on disk and the
// OpenAPI document use the same words.
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/jobs/job.h"
#include "server/jobs/job_record.h"

namespace voxd::server {
namespace {

TEST(JobStateNames, RecordsReadBackEveryStateAndTheContractListsThemInOrder) {
  std::vector<std::string> names;
  for (const auto& n : kJobStateNames) {
    EXPECT_EQ(job_state_from_string(n.name), n.value) << n.name;
    names.emplace_back(n.name);
  }
  EXPECT_FALSE(job_state_from_string("done"));
  std::ifstream in(std::string(VOXD_SOURCE_DIR) + "/proto-schemas/openapi.json");
  ASSERT_TRUE(in);
  const auto doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc.at(nlohmann::json::json_pointer("/components/schemas/JobStatus/properties/state")).at("enum"),
            nlohmann::json(names));
}

}  // namespace
}  // namespace voxd::server
