#include "api/param_error.h"

namespace voxd::api {
namespace {

std::string summarize(const std::vector<FieldError>& errors) {
  std::string s = "invalid job parameters:";
  for (const auto& e : errors) s += " " + (e.path.empty() ? std::string("(document)") : e.path) + ": " + e.message + ";";
  if (!errors.empty()) s.pop_back();
  return s;
}

}  // namespace

InvalidParams::InvalidParams(std::vector<FieldError> errors)
    : std::runtime_error(summarize(errors)), errors_(std::move(errors)) {}

}  // namespace voxd::api
