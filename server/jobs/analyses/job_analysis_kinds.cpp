// Every analysis kind's computing side, registered once, in the order of
// api::AnalysisKind (its request side: api/analyses/analysis_kinds.cpp).
#include <array>
#include <stdexcept>

#include "server/jobs/analyses/job_analysis_kind.h"

namespace voxd::server {

// Each defined in its own file under server/jobs/analyses/.
const JobAnalysisKind& report_analysis();
const JobAnalysisKind& radiography_analysis();
const JobAnalysisKind& section_analysis();
const JobAnalysisKind& preview_analysis();
const JobAnalysisKind& thickness_analysis();

const JobAnalysisKind& job_analysis_kind(api::AnalysisKind kind) {
  static const std::array<const JobAnalysisKind*, api::kAnalysisKindNames.size()> kinds{
      &report_analysis(), &radiography_analysis(), &section_analysis(), &preview_analysis(), &thickness_analysis()};
  for (const JobAnalysisKind* k : kinds)
    if (k->kind() == kind) return *k;
  throw std::logic_error("an analysis kind without its computing side");
}

std::string JobAnalysisKind::over_slabs(const AnalysisInput& in) const {
  throw std::logic_error(std::string("a ") + to_string(in.request.kind) + " request does not stream");
}

}  // namespace voxd::server
