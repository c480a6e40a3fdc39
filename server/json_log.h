#pragma once
// `voxd serve --log-format json`: one JSON object a line. A message that is
// a JSON value already (the request and job lines) is kept as it is; any
// other (a warning from deep inside, a third party's) becomes a JSON string,
// so no line is ever half JSON.
namespace voxd::server {

void use_json_log_lines();

}  // namespace voxd::server
