#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "api/result_json.h"
#include "server/cli/cli.h"
#include "server/cli/cli_output.h"
#include "server/cli/cli_args.h"
#include "server/cli/cli_params.h"
#include "server/mapped_file.h"
#include "server/pipeline/job_pipeline.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/encode/number_text.h"

namespace voxd::cli {
namespace {

// This run's volumes by name, for a mode that writes a format itself.
api::VolumeSource result_volumes(const VoxelJobResult& result) {
  return [&result](const std::string& name) {
    if (auto volume = result.volumes.volume(name)) return volume;
    throw Error(ErrorCode::invalid_argument, "this run made no volume named " + name);
  };
}

using nlohmann::json;

// Jobs whose volumes in memory would pass 512 MiB (2^32 voxels of bits,
// e.g. 1625^3; 1 Gi voxels of coverage) stream unless told otherwise, as in
// the service (JobLimits::stream_above_bytes): slab by slab is then as fast
// or faster (fresh memory costs page faults) and far smaller.

constexpr const char* kUsage = R"(usage: voxd voxelize MESH -o OUT [options]

Voxelizes MESH (STL, Draco, OBJ, PLY; detected from content) and writes the
volume to OUT ("-" for standard output).

  --params JSON|@FILE    job parameters, the same JSON the HTTP API takes
                         (proto-schemas/job-params.schema.json)
  --resolution N         voxels along the longest bounding-box axis
  --voxel-size H         voxel edge in millimetres
  --origin X,Y,Z         minimum corner of voxel (0,0,0) (with --voxel-size, --dims)
  --dims NX,NY,NZ        grid size in voxels (with --voxel-size, --origin)
  --padding P            empty voxels added on every side
  --mode M               one of the modes below (their options in --params,
                         under the mode's name: {"MODE": {...}})
  --inside T             auto (default: parity for a closed mesh, the winding
                         number otherwise) | parity | vote | winding (also the
                         sign of a distance field)
  --units U              the mesh file's unit: mm (default) | cm | m | in | ft;
                         grids, reports and outputs are in millimetres
  --format F             {formats}
                         (default: from OUT's extension; vox and png-stack (.zip)
                         hold colours, stl and glb a mode's own meshes)
  --raw-packing P        bytes (default) | bits, for --format raw
  --nrrd-encoding E      raw (default) | gzip, for --format nrrd
  --quantize Q           none (default) | u8 | u16: float values as rle levels
                         (value = offset + scale * level, both in the header)
  --threads N            worker threads (default: all cores)
  --device D             auto (default) | cpu | cuda: where a slice job's
                         colours, a coverage job's coverages and an sdf job's
                         band are computed (auto: a CUDA GPU, where one is,
                         for coverage, sdf and the noise functions on grids
                         of 2^21 voxels or more); the same bytes on either
  --streaming S          auto (default) | on | off: voxelize slab by slab and
                         write each slab as it is done, in bounded memory
                         (modes of bits with the parity inside test, and
                         coverage, to rle, raw or nrrd; not quantized);
                         auto streams past 512 MiB of volumes in memory
                         (2^32 voxels of bits)
  --max-voxels N         refuse grids with more voxels (default: 2^36, 8 GiB
                         of bits, in memory; no limit but disk when streamed)
  --report               include the mesh report (topology, area, volume)
  --json                 print the summary as JSON on standard output (on
                         standard error when OUT is -: the volume's bytes
                         are alone on standard output)

Flags override the matching fields of --params. A summary (grid, filled
voxels, volume, time per stage) is printed on standard error.
Without --params or a grid flag the grid is 128 voxels along the longest
bounding-box axis with no padding ({"resolution": 128}).

Modes (a mode that writes values reports as "filled" the solid, voxel
centres inside, that its values come with):
)";

// The usage with every mode's line (api/modes/).
std::string usage() {
  std::string text = with_format_list(kUsage);
  for (const api::JobMode* mode : api::job_modes()) {
    std::string name(mode->name());
    name.resize(std::max<std::size_t>(name.size() + 2, 15), ' ');
    text.append("  ").append(name).append(mode->summary()).append("\n");
  }
  return text;
}

std::string format_seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f s", s);
  return buf;
}

}  // namespace

int voxelize_command(int argc, char** argv) {
  Args args(argc, argv, 2,
            {"params", "resolution", "voxel-size", "origin", "dims", "padding", "mode", "inside", "units", "format",
             "raw-packing", "nrrd-encoding", "quantize", "threads", "output", "max-voxels", "streaming", "device"},
            {"json", "report", "help"});
  if (args.has("help")) {
    std::cout << usage();
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("voxelize takes exactly one mesh file (see voxd voxelize --help)");
  const OutputChoice output = read_output_choice(args, "voxelize");
  const std::string* const out_path = &output.path;
  const std::optional<VolumeFormat> format = output.format;
  EncodeOptions encode_options = output.options;

  json params_json = load_params(args);
  apply_param_flags(args, params_json);
  api::JobParams params = api::parse_job_params(params_json);

  if (encode_options.quantize != Quantize::none && !params.has_values())
    throw UsageError("--quantize applies to float values (a volume of type f32), not to bits");
  // A format that cannot hold the values is refused before any work.
  const bool mode_writes = params.mode->writes(*format);
  if (const auto probe = params.value_type(); probe && !mode_writes) {
    if (auto refusal = format_refusal(*probe, *format, encode_options)) throw UsageError("mode " + params.mode_name() + ": " + *refusal);
  } else if (!probe) {
    if (auto refusal = format_refusal(BitVolume(), *format)) throw UsageError("mode " + params.mode_name() + ": " + *refusal);
  }
  const int threads = thread_count(args);

  const std::string& mesh_path = args.positional()[0];
  MappedFile file(mesh_path);
  JobLimits limits;
  // In memory a local run may use the machine: 2^36 voxels is a 4096^3 grid
  // (8 GiB of bits). Streamed, the grid is bounded by kMaxGridDim alone.
  std::uint64_t max_voxels = std::uint64_t{1} << 36;
  const bool user_limit = args.value("max-voxels").has_value();
  if (auto m = args.value("max-voxels")) {
    const auto n = parse_number<std::uint64_t>(*m);
    if (!n || *n == 0) throw UsageError("--max-voxels expects a positive integer, got '" + *m + "'");
    max_voxels = *n;
  }
  const std::string streaming = args.value("streaming").value_or(api::to_string(params.streaming));
  if (streaming != "auto" && streaming != "on" && streaming != "off")
    throw UsageError("--streaming must be auto, on or off, got '" + streaming + "'");
  std::optional<std::string> no_stream = params.mode->streaming_refusal(params);
  if (!no_stream && mode_writes) no_stream = "the mode writes " + std::string(to_string(*format)) + " itself, from the whole result";
  if (!no_stream) {
    const std::optional<ValueVolume> probe = params.value_type();
    no_stream = probe ? streaming_refusal(*probe, *format, encode_options) : streaming_refusal(*format);
  }
  if (streaming == "on" && no_stream) throw UsageError("--streaming on: " + *no_stream);
  limits.max_voxels = user_limit || no_stream ? max_voxels : UINT64_MAX;
  // Streamed, the grid is bounded by kMaxGridDim alone, or the limit the user set.
  limits.max_streamed_voxels = user_limit ? max_voxels : UINT64_MAX;
  // The output, for the plan: a file that takes slabs unless it said why
  // not, runs when it is an RLE of bits, never kept whole.
  limits.output.no_slabs = no_stream;
  limits.output.takes_runs = !mode_writes && *format == VolumeFormat::rle;
  limits.output.keeps_volume = false;
  params.streaming = streaming == "on" ? api::Streaming::on : streaming == "off" ? api::Streaming::off : api::Streaming::automatic;
  PreparedVoxelJob job = prepare_voxel_job(file.bytes(), mesh_path, params, limits);
  const bool streamed = job.streamed;
  if (!streamed)  // the in-memory limit; a job that could stream is told so
    check_voxel_limit(job.grid, max_voxels,
                      no_stream || user_limit ? "" : " (or --streaming on: slab by slab it needs the memory of one slab, not the grid's)");
  encode_options.content = "voxels (1 = filled)";

  auto write_output = [&](const std::function<void(ByteSink&)>& encode) { return cli::write_output(*out_path, encode); };

  VoxelJobResult result;
  std::uint64_t bytes_written = 0;
  // An RLE of bits is made of runs: made straight from the crossings, the
  // grid is never a dense volume, streamed or not (the bytes are the same).
  const ExecutionPath path = job.path;
  if (path == ExecutionPath::runs) {
    const Grid grid = job.grid;
    bytes_written = write_output([&](ByteSink& sink) {
      BitSlabWriter writer(grid, *format, encode_options, sink);
      result = execute_voxel_runs_job(std::move(job), args.has("report"), nullptr, threads,
                                      [&](std::int64_t k0, const RunSlab& runs) { writer.write(k0, runs); },
                                      writer.preparer());
      writer.finish();
    });
  } else if (path == ExecutionPath::slabs) {
    const Grid grid = job.grid;
    const std::int64_t slab_layers = job.slab_layers;
    bytes_written = write_output([&](ByteSink& sink) {
      if (const std::optional<ValueVolume> probe = params.value_type()) {
        // The values are the output; the bits (the solid) are only counted.
        encode_options.content = params.mode->values_content(params);
        ValueSlabWriter writer(grid, *probe, *format, encode_options, sink);
        result = execute_streamed_voxel_job(
            std::move(job), args.has("report"), nullptr, threads, slab_layers, [](std::int64_t, const BitVolume&) {},
            [&](std::int64_t k0, const ValueVolume& slab) { writer.write(k0, slab); });
        writer.finish();
        return;
      }
      BitSlabWriter writer(grid, *format, encode_options, sink);
      result = execute_streamed_voxel_job(std::move(job), args.has("report"), nullptr, threads, slab_layers,
                                          [&](std::int64_t k0, const BitVolume& slab) { writer.write(k0, slab); });
      writer.finish();
    });
  } else {
    result = execute_voxel_job(std::move(job), args.has("report"), nullptr, threads);
    const api::JobVolumes& made = result.volumes;
    if (made.values) encode_options.content = api::volume_content(made.values_info);
    const auto start = std::chrono::steady_clock::now();
    bytes_written = write_output([&](ByteSink& sink) {
      if (mode_writes)
        params.mode->write(*format, params, result_volumes(result), sink);
      else if (made.values)
        encode_volume(*made.values, *format, sink, encode_options);
      else
        encode_volume(*made.solid, *format, sink, encode_options);
    });
    result.timings.add("encode", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  const Grid& g = result.grid;
  const double filled_volume = static_cast<double>(result.filled) * g.voxel_volume();
  if (args.has("json")) {
    json summary = {
        {"mesh", {{"path", mesh_path}, {"format", to_string(result.format)}, {"triangles", result.triangles}}},
        {"grid", api::to_json(g)},
        {"mode", params.mode_name()},
        {"inside", api::to_json(result.inside)},
        {"units", {{"mesh", to_string(params.units)}, {"lengths", "mm"}}},
        {"warnings", api::to_json(result.warnings)},
        {"filled_voxels", result.filled},
        {"filled_volume", filled_volume},
        {"streamed", result.streamed},
        {"execution", to_string(path)},
        {"output", {{"path", *out_path}, {"format", to_string(*format)}, {"bytes", bytes_written}}},
    };
    if (result.report) summary["report"] = api::to_json(*result.report);
    summary["values"] = result.volumes.values_info;
    json rot = json::array();
    for (int r = 0; r < 3; ++r) rot.push_back({result.rotation[0][r], result.rotation[1][r], result.rotation[2][r]});
    summary["rotation"] = rot;
    json timings = json::object();
    for (const auto& [name, s] : result.timings.stages) timings[name] = s;
    timings["total"] = result.timings.total();
    summary["timings"] = timings;
    // A volume on standard output keeps it to itself.
    (*out_path == "-" ? std::cerr : std::cout) << summary.dump(2) << '\n';
  } else {
    std::ostringstream s;
    s << "mesh:    " << mesh_path << " (" << to_string(result.format) << ", " << result.triangles << " triangles)\n";
    s << "grid:    " << g.dims.x << " x " << g.dims.y << " x " << g.dims.z << " voxels of " << g.voxel_size
      << " mm, origin [" << g.origin.x << ", " << g.origin.y << ", " << g.origin.z << "]"
      << (params.units != api::LengthUnit::mm ? std::string(" (mesh in ") + to_string(params.units) + ")" : "") << "\n";
    s << "inside:  " << to_string(result.inside.test)
      << (result.inside.reason.empty() ? std::string() : " (" + result.inside.reason + ")") << "\n";
    s << "filled:  " << result.filled << " voxels ("
      << 100.0 * static_cast<double>(result.filled) / static_cast<double>(g.voxel_count()) << "%), volume "
      << filled_volume << " mm^3\n";
    if (!result.volumes.values_info.is_null()) s << "values:  " << result.volumes.values_info.dump() << '\n';
    if (result.report)
      s << "mesh report: " << api::to_json(*result.report).dump() << '\n';
    s << "timings:";
    for (const auto& [name, sec] : result.timings.stages) s << ' ' << name << ' ' << format_seconds(sec) << ',';
    s << " total " << format_seconds(result.timings.total()) << '\n';
    s << "output:  " << *out_path << " (" << to_string(*format) << ", " << bytes_written << " bytes"
      << (result.streamed ? ", written slab by slab" : "") << ")\n";
    for (const api::JobWarning& w : result.warnings) s << "warning: " << w.message << " [" << w.code << "]\n";
    std::cerr << s.str();
  }
  return 0;
}

}  // namespace voxd::cli
