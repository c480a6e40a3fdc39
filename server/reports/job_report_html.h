#pragma once
// A job's report as one self-contained HTML file to send (GET /v1/jobs/{id}/
// report, the page's "Download report"): the verdict and its reason, the
// warnings, the inputs (file, units, grid and voxel size, mode, inside
// test, error bound, limits), the part's pictures painted by wall thickness
// (PNG previews, inline as data: URIs), and the report's tables. No script,
// no request to anywhere: it prints to PDF as it shows (A4, a print style
// sheet that keeps tables and pictures whole).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace voxd::server {

struct ReportPicture {
  std::string caption;
  std::string png;  // the image's bytes
};

// `status`: the job status JSON (job_status.h); `mode`: the job's mode by
// name (the status's params leave out a default); `report`: the analysis
// report JSON (proto-schemas/analysis.schema.json).
std::string job_report_html(const nlohmann::json& status, const std::string& mode, const nlohmann::json& report,
                            const std::vector<ReportPicture>& pictures);

}  // namespace voxd::server
