#pragma once
// One analysis a client asks for: the query of a /v1/jobs/{id}/<kind> route,
// or an entry of the job JSON's "analyses" array (the same names and values,
// plus "kind"), so a result prepared by the worker up front and one computed
// on first request are the same bytes under the same key.
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/skin_removal.h"
#include "voxd/enum_names.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::api {

// Which thickness a thickness volume holds: the wall thickness (the report's,
// voxd/analysis/wall_thickness.h) or BoneJ's local thickness
// (voxd/analysis/local_thickness.h).
enum class ThicknessMeasure { wall, local };
inline constexpr EnumNames<ThicknessMeasure, 2> kThicknessMeasureNames{
    {{ThicknessMeasure::wall, "wall"}, {ThicknessMeasure::local, "local"}}};
inline const char* to_string(ThicknessMeasure m) noexcept { return name_of(kThicknessMeasureNames, m); }

enum class AnalysisKind { analysis, radiography, section, preview, thickness };
inline constexpr EnumNames<AnalysisKind, 5> kAnalysisKindNames{{
    {AnalysisKind::analysis, "analysis"}, {AnalysisKind::radiography, "radiography"},
    {AnalysisKind::section, "section"}, {AnalysisKind::preview, "preview"}, {AnalysisKind::thickness, "thickness"}}};
inline const char* to_string(AnalysisKind kind) noexcept { return name_of(kAnalysisKindNames, kind); }

struct AnalysisRequest {
  AnalysisKind kind = AnalysisKind::analysis;
  // analysis: clean-up before measuring, wall thickness on/off, thin- and
  // thick-wall thresholds in model units.
  std::string cleanup = "none";  // none | debris | sheets
  bool thickness = true;
  // analysis: skin removal layers (false: "skin" is null; with
  // thickness=false and no clean-up the analysis streams over any grid).
  bool skin = true;
  std::optional<double> min_wall, max_wall;
  // radiography, section: the axis (0 = x).
  int axis = 2;
  // radiography: the measure; format png16 | png | json; unit voxels | model.
  // thickness: the measure (thickness_measure), format raw | rle | nrrd;
  // unit model | voxels.
  RadiographyMeasure measure = RadiographyMeasure::max;
  ThicknessMeasure thickness_measure = ThicknessMeasure::wall;
  std::string format;
  std::string unit;
  // section: exactly one of a voxel layer index or a model coordinate.
  std::optional<std::int64_t> index;
  std::optional<double> coordinate;
  // analysis: how the skin-removal layers are counted. radiography, section:
  // the model after `peel` layers of skin removal (0 = as voxelized).
  PeelMetric peel_metric = PeelMetric::faces;
  std::int64_t peel = 0;
  // section, preview: none | thickness (colour by wall thickness) | slice
  // (by a slice function: `slice`); section also distance (a distance
  // field's diverging map).
  std::string colour = "none";
  // section, preview with colour=slice: the slice function that colours the
  // job's solid (api/slice_options.h) and its canonical JSON text, the same
  // object a slice job of the same upload takes as `slice`.
  std::optional<SliceOptions> slice;
  std::string slice_json;
  // preview: +x | -x | +y | -y | +z | -z.
  std::string view = "+z";
  // preview: the image's longest side at most, in pixels (a larger view is
  // shrunk by an integer factor: voxd/analysis/preview.h); 0 = full size,
  // one pixel a voxel ("full").
  std::int64_t size = kDefaultPreviewSize;
  static constexpr std::int64_t kDefaultPreviewSize = 2048;

  // Every parameter of the kind, defaults included, in a fixed order, e.g.
  // "axis=z&measure=max&format=png16&unit=voxels": the route's canonical URL
  // query and, with the kind, the key its result is kept under (a slice
  // function's JSON by its SHA-256 there: a file name holds no JSON).
  std::string query() const;
  std::string peel_query() const;
  // "&slice=" and the slice JSON percent-encoded, for colour=slice; else "".
  std::string slice_query() const;
  // colour=slice: the solid coloured by `slice`.
  bool slice_coloured() const;
  std::string artifact_key() const;
  // MIME type of the result.
  const char* content_type() const;
};

// Field values as text, as they come in a URL query.
using Fields = std::vector<std::pair<std::string, std::string>>;

// Validates the fields of one request. Throws InvalidParams listing every
// problem, each at path_prefix + "/" + field name.
AnalysisRequest parse_analysis_request(AnalysisKind kind, const Fields& fields, const std::string& path_prefix);

// The job JSON's "analyses" array. Throws InvalidParams with paths such as
// "/analyses/2/axis".
std::vector<AnalysisRequest> parse_analyses(const nlohmann::json& analyses);

nlohmann::json to_json(const AnalysisRequest& request);

}  // namespace voxd::api
