#pragma once
// A tenant key's entry in a tenants file, made as docs/security.md tells an
// operator to make it (sha256sum), not as the service computes it.
#include <string>

#include <gtest/gtest.h>

#include "support/run_process.h"

namespace voxd::test {

inline std::string key_entry(const std::string& key) {
  const ProcessResult r = run_process("(printf %s '" + key + "' | sha256sum)");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return "sha256:" + r.out.substr(0, 64);
}

}  // namespace voxd::test
