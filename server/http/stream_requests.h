#pragma once
// Which requests are long-lived (an event stream, open for as long as its
// job runs), judged from the request line alone as the connection server
// must before any HTTP thread parses it: the connection server runs those on
// its stream threads. It reads the line as httplib's router will.
#include <string_view>

namespace voxd::server {

// Whether a request line ("GET /v1/jobs/ID/events?x HTTP/1.1") asks for an
// event stream.
bool is_event_stream_request(std::string_view request_line);

}  // namespace voxd::server
