#pragma once
// The route label of a request path in /metrics: the OpenAPI path template it
// matches ("/v1/jobs/{id}/layers/{k}"), else "other". Labels come only from
// the documented paths, so a client cannot grow the label set (and the
// metrics' memory) by inventing paths, ids or layer numbers.

#include <string>

namespace voxd::server {

std::string route_label(const std::string& path);

// Builds the label table now: it reads the served OpenAPI document, which
// the first request's log line should not wait for.
void prepare_route_labels();

}  // namespace voxd::server
