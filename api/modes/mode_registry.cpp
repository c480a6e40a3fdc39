// Every job mode, registered once: the order is the job JSON schema's
// (proto-schemas/job-params.schema.json "mode"), which error messages list.
#include <array>

#include "api/job_mode.h"

namespace voxd::api {

// Each defined in its own file under api/modes/.
const JobMode& solid_mode();
const JobMode& surface_mode();
const JobMode& solid_and_surface_mode();
const JobMode& coverage_mode();
const JobMode& sdf_mode();
const JobMode& palette_mode();
const JobMode& slice_mode();

std::span<const JobMode* const> job_modes() {
  static const std::array<const JobMode*, 7> modes{&solid_mode(),    &surface_mode(), &solid_and_surface_mode(),
                                                   &coverage_mode(), &sdf_mode(),     &palette_mode(),
                                                   &slice_mode()};
  return modes;
}

}  // namespace voxd::api
