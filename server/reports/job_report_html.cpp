#include "server/reports/job_report_html.h"

#include <openssl/evp.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace voxd::server {
namespace {

using nlohmann::json;

std::string escaped(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<int>(bytes.size()));
  out.resize(static_cast<std::size_t>(n));
  return out;
}

// A number as the page shows it: four significant digits; "–" for none.
std::string number(const json& v) {
  if (!v.is_number()) return "–";
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v.get<double>());
  return text;
}

std::string count(const json& v) { return v.is_number_integer() ? std::to_string(v.get<long long>()) : number(v); }

std::string vec(const json& v) {
  if (!v.is_array()) return "–";
  std::string out = "(";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + number(v[i]);
  return out + ")";
}

std::string text_of(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
}

std::string row(std::initializer_list<std::string> cells, bool head = false) {
  std::string out = "<tr>";
  for (const std::string& c : cells) out += (head ? "<th>" : "<td>") + escaped(c) + (head ? "</th>" : "</td>");
  return out + "</tr>\n";
}

// Regions (parts, voids, thin or thick walls): at most the first 20.
std::string regions(const std::string& title, const json& set, const char* extreme, const std::string& unit) {
  if (!set.is_object()) return "";
  std::string out = "<h3>" + escaped(title) + ": " + std::to_string(set.value("count", 0)) + "</h3>\n";
  const json& items = set.value("items", json::array());
  if (items.empty()) return out;
  out += "<table><thead>";
  out += extreme ? row({"#", "voxels", "volume (" + unit + "³)", "centroid", "thickness", "certain"}, true)
                 : row({"#", "voxels", "volume (" + unit + "³)", "centroid", "box min", "box max"}, true);
  out += "</thead><tbody>\n";
  for (std::size_t i = 0; i < items.size() && i < 20; ++i) {
    const json& r = items[i];
    if (extreme)
      out += row({std::to_string(i + 1), count(r.value("voxels", json())), number(r.value("volume", json())),
                  vec(r.value("centroid", json())), number(r.value(extreme, json())),
                  r.value("certain", false) ? "yes" : "marginal"});
    else
      out += row({std::to_string(i + 1), count(r.value("voxels", json())), number(r.value("volume", json())),
                  vec(r.value("centroid", json())), vec(r.value("bbox_min", json())), vec(r.value("bbox_max", json()))});
  }
  if (items.size() > 20) out += "<tr><td colspan=\"6\">… " + std::to_string(items.size() - 20) + " more</td></tr>\n";
  return out + "</tbody></table>\n";
}

constexpr const char* kStyle = R"(
body { font: 11pt/1.4 system-ui, sans-serif; color: #1d2330; margin: 2em auto; max-width: 60em; padding: 0 1em; }
h1 { font-size: 1.6em; margin: 0 0 .2em; } h2 { font-size: 1.2em; margin: 1.4em 0 .4em; } h3 { font-size: 1em; margin: 1em 0 .3em; }
.muted { color: #6b7385; }
.verdict { font-size: 1.3em; font-weight: 700; padding: .3em .8em; border-radius: 4px; display: inline-block; }
.verdict.pass { background: #dff3e4; color: #1e7b34; } .verdict.fail { background: #fdecea; color: #b3261e; }
.verdict.inconclusive { background: #fff4d6; color: #a86200; } .verdict.none { background: #eef0f4; }
table { border-collapse: collapse; margin: .3em 0 1em; font-size: .95em; }
th, td { border: 1px solid #d9dde6; padding: .15em .5em; text-align: right; }
th { background: #f1f4fb; } td:first-child, th:first-child { text-align: left; }
.warnings li { color: #a86200; }
table.inputs td { text-align: left; }
.pictures { display: flex; flex-wrap: wrap; gap: 1em; }
figure { margin: 0; } figure img { width: 16em; border: 1px solid #d9dde6; image-rendering: pixelated; }
figcaption { font-size: .9em; color: #6b7385; }
@page { size: A4; margin: 15mm; }
@media print { body { margin: 0; max-width: none; } table, figure { break-inside: avoid; } h2 { break-after: avoid; } }
)";

}  // namespace

std::string job_report_html(const json& status, const std::string& mode, const json& report,
                            const std::vector<ReportPicture>& pictures) {
  const std::string id = text_of(status, "id");
  const std::string name = text_of(status, "name").empty() ? id : text_of(status, "name");
  const std::string unit = report.value("unit", "mm");
  const json& grid = status.value("grid", json::object());
  const json& params = status.value("params", json::object());
  const json& t = report.value("thickness", json());
  const std::string verdict = t.is_object() && t.value("verdict", json()).is_string() ? t["verdict"].get<std::string>() : "";

  std::string h = "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>voxd report: " +
                  escaped(name) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  h += "<h1>" + escaped(name) + "</h1>\n<p class=\"muted\">voxd job " + escaped(id) + ", made " +
       escaped(text_of(status, "created_at")) + "</p>\n";

  h += "<h2>Wall thickness verdict</h2>\n<p><span class=\"verdict " + (verdict.empty() ? std::string("none") : verdict) +
       "\">" + (verdict.empty() ? std::string("no limits given") : escaped(verdict)) + "</span></p>\n";
  if (t.is_object()) {
    if (!text_of(t, "verdict_reason").empty()) h += "<p class=\"verdict-reason\">" + escaped(text_of(t, "verdict_reason")) + "</p>\n";
    h += "<p>min " + number(t.value("min", json())) + ", mean " + number(t.value("mean", json())) + ", max " +
         number(t.value("max", json())) + " " + escaped(unit) + "; min wall " + number(t.value("min_wall", json())) +
         ", max wall " + number(t.value("max_wall", json())) + "</p>\n";
    if (t.value("voxel_size_to_decide", json()).is_number())
      h += "<p>voxel size to decide: " + number(t["voxel_size_to_decide"]) + " " + escaped(unit) + " or smaller</p>\n";
  }
  const json& warnings = status.value("warnings", json::array());
  if (!warnings.empty()) {
    h += "<h2>Warnings</h2>\n<ul class=\"warnings\">\n";
    for (const json& w : warnings) h += "<li>" + escaped(text_of(w, "message")) + "</li>\n";
    h += "</ul>\n";
  }

  h += "<h2>Inputs</h2>\n<table class=\"inputs\"><tbody>\n";
  h += row({"file", text_of(status, "name").empty() ? "–" : text_of(status, "name")});
  h += row({"mesh units", params.value("units", json("mm")).is_string() ? params.value("units", std::string("mm")) : "mm"});
  h += row({"mode", mode});
  const json& dims = grid.value("dims", json::array());
  h += row({"grid", dims.size() == 3 ? std::to_string(dims[0].get<long long>()) + " × " +
                                            std::to_string(dims[1].get<long long>()) + " × " +
                                            std::to_string(dims[2].get<long long>()) + " voxels"
                                      : "–"});
  h += row({"voxel size", number(grid.value("voxel_size", json())) + " " + unit});
  const json& inside = status.value("inside", json());
  h += row({"inside test", inside.is_object() ? text_of(inside, "test") + (text_of(inside, "reason").empty() ? "" : " (" + text_of(inside, "reason") + ")")
                                              : "–"});
  if (t.is_object()) h += row({"error bound", text_of(t, "error_bound")});
  h += "</tbody></table>\n";

  if (!pictures.empty()) {
    h += "<h2>The part by wall thickness</h2>\n<div class=\"pictures\">\n";
    for (const ReportPicture& p : pictures)
      h += "<figure><img alt=\"" + escaped(p.caption) + "\" src=\"data:image/png;base64," + base64(p.png) +
           "\"><figcaption>" + escaped(p.caption) + "</figcaption></figure>\n";
    h += "</div>\n";
  }

  const json& m = report.value("mass_properties", json::object());
  const json& voxels = m.value("voxels", json::object());
  const json& mesh = m.value("mesh", json::object());
  const bool exact = mesh.is_object() && mesh.value("available", true);
  h += "<h2>Mass properties (" + escaped(unit) + ")</h2>\n<table><thead>" + row({"", "voxels", "mesh (exact)"}, true) +
       "</thead><tbody>\n";
  h += row({"volume", number(voxels.value("volume", json())), exact ? number(mesh.value("volume", json())) : "–"});
  h += row({"centroid", vec(voxels.value("centroid", json())), exact ? vec(mesh.value("centroid", json())) : "–"});
  h += row({"surface area", "–", exact ? number(mesh.value("surface_area", json())) : "–"});
  h += "</tbody></table>\n";
  if (!exact && !text_of(mesh, "reason").empty()) h += "<p class=\"muted\">mesh (exact): " + escaped(text_of(mesh, "reason")) + "</p>\n";

  h += "<h2>Parts and voids</h2>\n";
  h += regions("Parts", report.value("parts", json()), nullptr, unit);
  h += regions("Voids", report.value("voids", json()), nullptr, unit);
  if (t.is_object()) {
    h += "<h2>Wall thickness regions</h2>\n";
    h += regions("Thin regions", t.value("thin_regions", json()), "min_thickness", unit);
    h += regions("Thick regions", t.value("thick_regions", json()), "max_thickness", unit);
  }
  h += "<p class=\"muted\">Made by voxd; every value in " + escaped(unit) + ".</p>\n</body>\n</html>\n";
  return h;
}

}  // namespace voxd::server
