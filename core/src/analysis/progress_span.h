#pragma once
// A stage's share of a job's progress bar, so a stage that runs inside a
// larger one (the distance transform inside local thickness) reports a
// fraction of the whole job instead of restarting at 0.
#include "voxd/progress.h"

namespace voxd::detail {

struct ProgressSpan {
  JobControl* control = nullptr;
  double begin = 0.0;
  double end = 1.0;

  void check_cancelled() const {
    if (control) control->check_cancelled();
  }
  // `fraction` of this stage done.
  void report(double fraction) const {
    if (control) control->set_progress(begin + (end - begin) * fraction);
  }
  ProgressSpan part(double from, double to) const {
    return {control, begin + (end - begin) * from, begin + (end - begin) * to};
  }
};

}  // namespace voxd::detail
