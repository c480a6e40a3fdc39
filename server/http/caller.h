#pragma once
// Who is asking, for the request being answered on this thread: the tenant
// its key names (server/tenants/tenant_directory.h). Set by the middleware
// before any route runs, on the thread that runs the route (an HTTP thread,
// or the stream thread an event stream is served on).
#include <string>

#include "server/jobs/job.h"
#include "server/tenants/tenant_directory.h"

namespace voxd::server {

struct Caller {
  Tenant tenant;  // the unnamed tenant "" when the service has no keys
  // Whether this caller may see, fetch and remove `job`: its own tenant's,
  // or any for an admin.
  bool sees(const JobSnapshot& job) const { return tenant.admin || job.labels.tenant == tenant.name; }
  // The jobs a listing shows it.
  JobFilter jobs() const {
    JobFilter f;
    if (!tenant.admin) f.tenant = tenant.name;
    return f;
  }
};

const Caller& current_caller();
void set_current_caller(Caller caller);

}  // namespace voxd::server
