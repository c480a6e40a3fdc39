#pragma once
// A JSON answer. Strings that are not UTF-8 (a file name, a path) are
// replaced, never thrown over.
#include <httplib.h>
#include <nlohmann/json.hpp>

namespace voxd::server {

inline void send_json(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

}  // namespace voxd::server
