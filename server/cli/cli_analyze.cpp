// `voxd analyze`: the job's voxelization followed by the manufacturing
// analysis, written into a directory as the HTTP API serves it.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>

#include "api/analysis_json.h"
#include "api/job_params.h"
#include "server/cli/cli.h"
#include "server/cli/cli_args.h"
#include "server/cli/cli_params.h"
#include "server/mapped_file.h"
#include "server/pipeline/job_pipeline.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/kept_mesh.h"
#include "voxd/analysis/analysis.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/number_text.h"
#include "voxd/error.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/mesh_report.h"

namespace voxd::cli {
namespace {

constexpr const char* kUsage = R"(usage: voxd analyze MESH -o DIR [options]

Voxelizes MESH with the job parameters, then analyses the voxel model and
writes into DIR what the HTTP API serves for a job:
  analysis.json          mass properties from the mesh (when it is closed) and
                         from the voxels side by side, connected parts,
                         enclosed voids, skin removal layers and hot spots,
                         wall thickness with thin and thick regions
  radiography-{x,y,z}-{min,max,total}.png
                         16-bit, one pixel value = one voxel (scale in tEXt)
  radiography-{x,y,z}-max-colour.png   false colour with a legend
  section-{x,y,z}.png    the middle layer; section-*-thickness.png coloured
                         by wall thickness
  preview-from{+x,-x,+y,-y,+z,-z}.png  shaded views; preview-*-thickness.png
                         coloured by wall thickness
  thickness.nrrd         the wall-thickness volume (float32, mm)
  thickness-on-part.{ply,glb,json}
                         the mesh (welded, as given) with each vertex's wall
                         thickness and colour (between --min-wall and
                         --max-wall where given), and the values per vertex
                         with the thin region of each
  analyses/KEY.EXT       each entry of the job JSON's "analyses" array
Each file is what the service's route answers for the same job (the
radiography, section, preview and thickness routes with their defaults):
with a mode of values the sections and previews show the values as the
service's do (grey coverage, a distance field's zero level set ray-marched
and section-{x,y,z}-distance.png as a diverging map, colours); the
measurements are of the solid.
Lengths are in millimetres (--units gives the mesh file's unit). The
thickness files need the wall thickness (not with --no-thickness or --cleanup*).

  --params JSON|@FILE    job parameters, as for voxd voxelize and the HTTP API
  --resolution N, --voxel-size H, --origin X,Y,Z, --dims NX,NY,NZ, --padding P,
  --mode M, --inside T, --units U
                         as for voxd voxelize
  --min-wall T           report regions thinner than T (mm): thin walls
  --max-wall T           report regions thicker than T (mm): hot spots
  --min-region N         ignore thin/thick regions under N voxels (default 1)
  --no-thickness         skip wall thickness (the slowest step)
  --cleanup              remove isolated voxels and one-voxel lines first
  --cleanup-sheets       also remove one-voxel-thick sheets
  --threads N            worker threads (default: all cores)
)";

}  // namespace

int analyze_command(int argc, char** argv) {
  std::set<std::string> valued(std::begin(kParamFlags), std::end(kParamFlags));
  valued.insert({"output", "threads", "min-wall", "max-wall", "min-region"});
  Args args(argc, argv, 2, valued, {"cleanup", "cleanup-sheets", "no-thickness", "help"});
  if (args.has("help")) {
    std::cout << kUsage;
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("analyze takes exactly one mesh file (see voxd analyze --help)");
  const auto out_dir = args.value("output");
  if (!out_dir || out_dir->empty()) throw UsageError("analyze needs -o DIR (see voxd analyze --help)");
  nlohmann::json params_json = load_params(args);
  apply_param_flags(args, params_json);
  const api::JobParams params = api::parse_job_params(params_json);
  const int threads = thread_count(args);

  const std::string& mesh_path = args.positional()[0];
  MappedFile file(mesh_path);
  JobLimits limits;
  limits.max_voxels = std::uint64_t{1} << 33;
  limits.welds_mesh = true;  // for the kept mesh below
  PreparedVoxelJob prepared = prepare_voxel_job(file.bytes(), mesh_path, params, limits);
  // The mesh the thickness on the part is painted on, kept as the service
  // keeps a job's (before the voxelizer turns it).
  std::map<std::string, std::string> kept;
  if (!prepared.welded) prepared.welded = std::make_shared<const Mesh>(weld_vertices(prepared.mesh));  // the mesh report reads it too
  kept[server::kKeptMeshKey] = server::encode_kept_mesh(*prepared.welded, prepared.rotation);
  VoxelJobResult result = execute_voxel_job(std::move(prepared), /*with_report=*/true, nullptr, threads);

  auto positive = [&](const char* flag) -> double {
    const auto v = args.value(flag);
    if (!v) return 0.0;
    const double x = parse_number_list(*v, 1, flag)[0];
    if (!(x > 0)) throw UsageError(std::string("--") + flag + " must be a positive length in millimetres");
    return x;
  };
  AnalysisOptions options;
  options.threads = threads;
  options.thickness = !args.has("no-thickness");
  options.min_wall_voxels = positive("min-wall") / result.grid.voxel_size;
  options.max_wall_voxels = positive("max-wall") / result.grid.voxel_size;
  if (auto n = args.value("min-region")) {
    const auto voxels = parse_number<std::uint64_t>(*n);
    if (!voxels) throw UsageError("--min-region expects a number of voxels");
    options.min_region_voxels = *voxels;
  }
  if (args.has("cleanup") || args.has("cleanup-sheets")) options.cleanup = CleanupOptions{true, true, args.has("cleanup-sheets")};
  // One wall thickness map for the report, the images and the volume.
  std::shared_ptr<const DenseVolume<float>> map;
  if (options.thickness && !options.cleanup) {
    map = std::make_shared<const DenseVolume<float>>(wall_thickness(*result.volumes.solid, threads));
    options.thickness_map = map.get();
  }
  const AnalysisReport report = analyze_volume(*result.volumes.solid, options);
  nlohmann::json doc = api::analysis_to_json(report, result.grid, result.report, result.mesh_mass);
  doc["inside"] = api::to_json(result.inside);
  doc["warnings"] = api::to_json(result.warnings);

  std::filesystem::create_directories(*out_dir);
  const std::string path = *out_dir + "/analysis.json";
  {
    std::ofstream out(path + ".partial");
    out << doc.dump(2) << '\n';
    if (!out) throw Error(ErrorCode::io_error, "cannot write " + path);
  }
  std::filesystem::rename(path + ".partial", path);
  // Every file beside analysis.json is what the service answers for the
  // same job: made by the function its routes call (server::job_analysis)
  // from the request the route takes, so the bytes and their metadata agree.
  // This run's wall-thickness map is handed over as it is.
  const server::ArtifactAccess artifacts{
      "cli", [&kept](const std::string& key) -> std::optional<std::string> {
        auto it = kept.find(key);
        if (it == kept.end()) return std::nullopt;
        return it->second;
      },
      // Only the thickness maps are worth keeping: every other result is
      // written once and never asked for again.
      [&kept](const std::string& key, std::string_view bytes) {
        if (key == server::thickness_map_key(api::ThicknessMeasure::local)) kept[key] = bytes;
      },
      map};
  server::JobSnapshot job;
  job.id = "cli";
  job.params = params_json;
  job.job = std::make_shared<const api::JobParams>(params);
  job.grid = result.grid;
  job.mesh = result.report;
  job.inside = result.inside;
  job.warnings = result.warnings;
  job.mesh_mass = result.mesh_mass;
  job.values = result.volumes.values_info;
  server::JobOutput output;
  static_cast<api::JobVolumes&>(output) = result.volumes;  // shared, not copied

  std::size_t files = 0;
  auto write_file = [&](const std::string& name, const std::string& bytes) {
    const std::string file = *out_dir + "/" + name;
    FileSink sink(file + ".partial");
    sink.write(bytes.data(), bytes.size());
    sink.close();
    std::filesystem::rename(file + ".partial", file);
    ++files;
  };
  auto answer = [&](const api::AnalysisRequest& request, const std::string& where) {
    try {
      return server::job_analysis(request, job, output, artifacts).bytes;
    } catch (const server::AnalysisRejected& e) {
      throw Error(ErrorCode::invalid_argument, where + ": " + e.what());
    }
  };
  auto request = [](api::AnalysisKind kind, const api::Fields& fields) { return api::parse_analysis_request(kind, fields, ""); };
  using api::AnalysisKind;
  const bool distances = result.volumes.values && params.mode->distance_field(params, *result.volumes.values).has_value();
  std::vector<std::pair<std::string, api::AnalysisRequest>> standard;
  for (int axis = 0; axis < 3; ++axis) {
    const std::string a(1, "xyz"[axis]);
    for (const char* m : {"min", "max", "total"})
      standard.emplace_back("radiography-" + a + "-" + m + ".png", request(AnalysisKind::radiography, {{"axis", a}, {"measure", m}}));
    standard.emplace_back("radiography-" + a + "-max-colour.png",
                          request(AnalysisKind::radiography, {{"axis", a}, {"measure", "max"}, {"format", "png"}}));
    const api::Fields middle = {{"axis", a}, {"index", std::to_string(result.grid.dims[axis] / 2)}};
    standard.emplace_back("section-" + a + ".png", request(AnalysisKind::section, middle));
    auto coloured = [&](const char* colour) {
      api::Fields f = middle;
      f.emplace_back("colour", colour);
      return request(AnalysisKind::section, f);
    };
    if (map) standard.emplace_back("section-" + a + "-thickness.png", coloured("thickness"));
    if (distances) standard.emplace_back("section-" + a + "-distance.png", coloured("distance"));
  }
  for (const char* view : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    standard.emplace_back(std::string("preview-from") + view + ".png", request(AnalysisKind::preview, {{"view", view}}));
    if (map)
      standard.emplace_back(std::string("preview-from") + view + "-thickness.png",
                            request(AnalysisKind::preview, {{"view", view}, {"colour", "thickness"}}));
  }
  if (map) {
    standard.emplace_back("thickness.nrrd", request(AnalysisKind::thickness, {{"format", "nrrd"}}));
    // And on the part itself, coloured between --min-wall and --max-wall
    // where given, as GET /v1/jobs/{id}/thickness?format=ply|glb|json&...
    api::Fields on_part;
    if (args.value("min-wall")) on_part.emplace_back("min_wall", *args.value("min-wall"));
    if (args.value("max-wall")) on_part.emplace_back("max_wall", *args.value("max-wall"));
    for (const char* format : {"ply", "glb", "json"}) {
      api::Fields f = on_part;
      f.emplace_back("format", format);
      standard.emplace_back(std::string("thickness-on-part.") + format, request(AnalysisKind::thickness, f));
    }
  }
  for (const auto& [name, r] : standard) write_file(name, answer(r, name));

  // The job JSON's analyses, named by their keys.
  if (!params.analyses.empty()) {
    std::filesystem::create_directories(*out_dir + "/analyses");
    for (std::size_t i = 0; i < params.analyses.size(); ++i) {
      const api::AnalysisRequest& r = params.analyses[i];
      const std::string type = r.content_type();
      const char* ext = type == "application/json" ? ".json" : type == "image/png" ? ".png"
                        : type == "application/x-nrrd" ? ".nrrd" : type == "application/vnd.voxd.rle" ? ".rle" : ".raw";
      write_file("analyses/" + r.artifact_key() + ext, answer(r, "analyses/" + std::to_string(i)));
    }
  }
  std::cerr << "analysis: " << report.components.parts.size() << " part(s), " << report.components.voids.size()
            << " void(s), skin " << (report.skin ? report.skin->max_depth : 0) << " layers deep; wrote " << path << " and " << files
            << " files\n";
  if (report.thickness && !doc["thickness"]["verdict"].is_null())
    std::cerr << "verdict: " << doc["thickness"]["verdict"].get<std::string>() << " ("
              << doc["thickness"]["verdict_reason"].get<std::string>() << ")\n";
  for (const api::JobWarning& w : result.warnings) std::cerr << "warning: " << w.message << " [" << w.code << "]\n";
  return 0;
}

}  // namespace voxd::cli
