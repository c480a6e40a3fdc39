#pragma once
// A job's mode (the job JSON's "mode") as one unit:
// everything the pipeline, the job store, the HTTP routes and the CLI need to
// know about it, so they ask the mode instead of testing its name. Each mode
// lives in its own file under api/modes/ and is listed once in
// api/modes/mode_registry.cpp (docs/architecture.md: "Adding a mode").
//
// A mode says:
//  - its JSON options (the object under its own name) and how they are
//    validated, and what else of the job JSON it accepts or refuses;
//  - the memory its volumes take at peak;
//  - how it runs: the engine call that makes the job's bits and values;
//  - what it makes: bits, or values of which type, and extra named volumes
//    kept beside them (a similarity per voxel);
//  - the formats it writes itself (a reconstruction as a mesh), the volumes a client
//    can ask for by ?layer=, and the JSON documents it serves
//    (GET /v1/jobs/{id}/<document>);
//  - how its values read as an image (a distance field's shading).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "voxd/analysis/sdf_render.h"
#include "voxd/bit_volume.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/run_slab.h"
#include "voxd/voxelize/streamed.h"
#include "voxd/voxelize/voxelize.h"
#include "api/job_volumes.h"

namespace voxd::api {

class ParamValidator;
struct JobParams;

// A mode's parsed options; each mode derives its own.
struct ModeOptions {
  virtual ~ModeOptions() = default;
};

// What a mode's run is given: the mesh in the engine's frame (rotated, and
// divided by the voxel aspect), the grid, the parsed job.
struct ModeInput {
  const Mesh& mesh;
  const Grid& grid;
  const JobParams& params;
  int threads = 0;
  JobControl* control = nullptr;
  // The parity solid, made first when the mode asks for it (needs_parity_solid).
  const BitVolume* parity_solid = nullptr;
  // A streamed run of only these z layers (one part of a job spread over
  // workers); honoured by run_runs (JobMode::makes_runs), the whole grid
  // for the other runs.
  LayerRange layers{};
  // run_runs: the consumer's work on each slab done where it is made, in
  // parallel, before the consumer takes it (voxelize_runs' `prepare`).
  RunSlabPreparer prepare_runs{};
};

// The volumes of a finished job, by name: "values" (the result) and each
// stored layer. Returns null for one the job does not have.
using VolumeSource = std::function<std::shared_ptr<const ValueVolume>(const std::string& name)>;

// A request the job's mode cannot answer (an unknown layer): HTTP 400
// invalid-query, with this message.
class QueryRejected : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JobMode {
 public:
  virtual ~JobMode() = default;

  // The JSON "mode" value, which is also the key of its options object.
  virtual std::string_view name() const = 0;
  // One line for `voxd voxelize --help`: what the result is.
  virtual std::string_view summary() const = 0;

  // --- The job JSON ---
  // Whether the mode takes an options object under its name.
  virtual bool has_options() const { return false; }
  // Parses the options object (null when the job JSON has none) into the
  // mode's options; problems go to `val`.
  virtual std::shared_ptr<ModeOptions> parse_options(ParamValidator& val, const nlohmann::json* options,
                                                     const JobParams& params) const;
  // Checks and completes the options against the rest of the job JSON once
  // all of it is read (the inside test, the grid).
  virtual void complete(ParamValidator& val, const nlohmann::json& job, JobParams& params) const;

  // --- What it makes ---
  // The voxelization of the job's bits for a mode that makes only bits.
  virtual VoxelMode voxel_mode() const { return VoxelMode::solid; }
  // An empty volume of the result's value type, to ask format_refusal()
  // before any work; nullopt for a result of bits.
  virtual std::optional<ValueVolume> value_type(const JobParams& params) const;
  // The voxel's edges over the grid's voxel_size (anisotropic voxels): the
  // engine runs where the voxels are cubes, i.e. on coordinates / aspect.
  virtual glm::dvec3 voxel_aspect(const JobParams& params) const;
  // Bytes its volumes take at peak, for admission control.
  virtual std::uint64_t memory_estimate(const Grid& grid, const JobParams& params) const;

  // --- How it runs ---
  // Whether the job's inside test applies ("inside", chosen from the mesh
  // by "auto"); false for a mode that counts crossings itself, which is
  // parity whatever the mesh (and refuses the key).
  virtual bool uses_inside_test() const { return true; }
  // Whether part of its run can go to a GPU (voxd/compute_device.h): a job
  // of another mode that asks for device cuda is refused.
  virtual bool runs_on_gpu() const { return false; }
  // Whether the job's bits are the parity solid of the mesh, made before
  // run() (which then makes only the values).
  virtual bool needs_parity_solid(const JobParams& params) const;
  // The timing stage's name.
  virtual std::string_view stage_name() const { return name(); }
  // What it makes (api/job_volumes.h): its bits unless it needs the parity
  // solid, its values, the layers kept beside them and what the values are
  // ("type" is added after).
  virtual JobVolumes run(const ModeInput& in) const = 0;
  // Slab-streamed runs (voxd/voxelize/streamed.h), for grids larger than
  // memory: nullopt when this job's result can be made slab by slab, else
  // why not, in words for the user. run_streamed hands each finished z-slab
  // of the job's bits to `bits` (unless the pipeline makes the parity solid
  // first: needs_parity_solid) and of its values to `values`, and returns
  // what run() says in JobVolumes::values_info.
  virtual std::optional<std::string> streaming_refusal(const JobParams& params) const;
  // Whether a job that can stream is faster slab by slab than in memory
  // whatever its size (the band SDF: no whole float volume to clear), so an
  // output that streams is made so even below the memory threshold.
  virtual bool faster_in_slabs(const JobParams&) const { return false; }
  virtual nlohmann::json run_streamed(const ModeInput& in, std::int64_t slab_layers, const BitSlabConsumer& bits,
                                      const ValueSlabConsumer& values) const;
  // Whether the job's bits can be made as runs (voxd/voxelize/runs.h): a
  // job of bits only, each row of voxels made on its own from its crossings.
  // Such a job is written to a format made of runs (the RLE) without a dense
  // volume, and any range of its z layers can be made alone (ModeInput::
  // layers), bit for bit the whole run's, so that a huge job splits into
  // slab tasks for many workers (server/jobs/slab_tasks.h). run_runs hands
  // each slab of runs to `runs` in z order.
  virtual bool makes_runs(const JobParams&) const { return false; }
  virtual void run_runs(const ModeInput& in, const RunSlabConsumer& runs) const;
  // Bytes one z layer takes in a streamed run (what it holds per layer of a
  // slab at once), to size slabs and admit the job.
  virtual std::uint64_t streamed_layer_bytes(const Grid& grid, const JobParams& params) const;
  // What the values are in words, for a format's header ("content:" in
  // NRRD) written before a streamed run says it in values_info.
  virtual std::string values_content(const JobParams& params) const;

  // --- What it serves ---
  // Formats the mode writes itself rather than as a volume.
  virtual bool writes(VolumeFormat format) const;
  virtual void write(VolumeFormat format, const JobParams& params, const VolumeSource& volumes, ByteSink& sink) const;
  // Volumes a client can ask for with ?layer=NAME, the first being the
  // result, and those stored beside it (a subset, made by run()).
  virtual std::vector<std::string> layer_names() const { return {}; }
  // What ?layer=NAME holds in words (NRRD's "content:"), given the job's
  // "values"; by default the values' own.
  virtual std::string layer_content(const std::string& layer, const nlohmann::json& values_info) const;
  virtual std::vector<std::string> stored_layers() const { return {}; }
  // The volume `layer` names; throws QueryRejected for a layer it cannot give.
  virtual std::shared_ptr<const ValueVolume> layer(const std::string& layer, const JobParams& params,
                                                   const VolumeSource& volumes) const;
  // JSON documents served at GET /v1/jobs/{id}/<name>.
  virtual std::vector<std::string> documents() const { return {}; }
  virtual nlohmann::json document(const std::string& name, const JobParams& params, const VolumeSource& volumes) const;

  // --- How its values read ---
  // Whether the values are signed distances.
  virtual bool distance_values() const { return false; }
  // A distance field's values and their convention, for distance sections
  // and shaded previews; nullopt when the values are not distances.
  virtual std::optional<SdfRenderInput> distance_field(const JobParams& params, const ValueVolume& values) const;
  // Whether a section of the values is a picture of them (false: indices
  // into a table, whose sections show the solid instead).
  virtual bool values_are_image() const { return true; }
  // Whether the values are RGBA colours: served as one PNG per z layer
  // (GET /v1/jobs/{id}/layers/{k}), shown by colour sections and previews.
  virtual bool colour_values() const { return false; }
};

// A mode with an options object of type `Options` (a ModeOptions): it
// parses them with parse(), called with the object when the job JSON has one
// and with null when it has none (defaults, or a "required" problem).
template <class Options>
class ModeWithOptions : public JobMode {
 public:
  bool has_options() const override { return true; }
  std::shared_ptr<ModeOptions> parse_options(ParamValidator& val, const nlohmann::json* options,
                                             const JobParams&) const override {
    auto out = std::make_shared<Options>();
    parse(val, options, *out);
    return out;
  }

 protected:
  virtual void parse(ParamValidator& val, const nlohmann::json* options, Options& out) const = 0;
  // The job's options (defined in api/job_params.h, where JobParams is complete).
  static const Options& options(const JobParams& params);
  static Options& options(JobParams& params);
};

// Every mode, in the order the job JSON schema lists them.
std::span<const JobMode* const> job_modes();
// The mode named `name`, or null.
const JobMode* find_job_mode(std::string_view name);
// The modes that have `has` (a document, a layer), as "\"a\" or \"b\"" for
// messages that say which modes would answer.
std::string modes_with(const std::function<bool(const JobMode&)>& has);

// Bytes of the job's bit volumes: one, three for the vote test (its three
// axes), one more for solid+surface.
std::uint64_t bit_volumes_memory(const Grid& grid, VoxelMode mode, InsideTest inside);

// For a mode whose solid comes from counting crossings: the inside test does
// not apply, and a job JSON that sets one is refused.
void refuse_inside_test(ParamValidator& val, const nlohmann::json& job, std::string_view mode);

}  // namespace voxd::api
