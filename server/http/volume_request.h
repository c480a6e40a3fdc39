#pragma once
// A request for a job's volume (GET /v1/jobs/{id}/volume, POST /v1/voxelize):
// its query (format, quantize, encoding, packing), the refusals of a format
// that cannot hold the job's result, and the streamed answer.
#include <memory>
#include <string>

#include <httplib.h>

#include "api/job_params.h"
#include "server/jobs/job.h"
#include "server/jobs/stored_blob.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {

class Metrics;

struct VolumeRequest {
  VolumeFormat format = VolumeFormat::rle;
  EncodeOptions options;
  bool gzip = false;  // the client accepts a gzip-encoded answer
};

// The query's volume parameters; a 400 problem naming the one that is wrong.
VolumeRequest read_volume_request(const httplib::Request& req);

// What a job's volume (or its ?layer=) holds, for the NRRD "content:" line.
std::string volume_content(const JobSnapshot& job, const std::string& layer = "");

// Refuses, before any work, a format that cannot hold the job's result.
void check_format_holds(const api::JobParams& params, const VolumeRequest& v);
// Refuses, before reading the volume, a format or option that bits cannot take.
void check_bits_format(const VolumeRequest& v);

// Streams a volume of values, or refuses the format with a 400 problem.
void answer_values(httplib::Response& res, std::shared_ptr<const ValueVolume> values, const VolumeRequest& v,
                   const std::string& filename, Metrics& metrics);
void answer_bits(httplib::Response& res, std::shared_ptr<const BitVolume> bits, const VolumeRequest& v,
                 const std::string& filename, Metrics& metrics);
// Streams a streamed job's stored RLE (server/jobs/job_store.h) in the
// requested format slab by slab, never loading the grid: rle as stored, raw
// and nrrd re-encoded as they are read (voxd/encode/slab_writer.h). A format
// that does not stream (binvox) is refused here: the caller loads the
// volume whole when it fits.
void answer_stored_bits(httplib::Response& res, std::shared_ptr<const StoredBlob> rle, const VolumeRequest& v,
                        const std::string& filename, Metrics& metrics);

// The same for a streamed job's stored values on `grid`, of `type`'s type.
void answer_stored_values(httplib::Response& res, std::shared_ptr<const StoredBlob> rle, const Grid& grid,
                          const ValueVolume& type, const VolumeRequest& v, const std::string& filename, Metrics& metrics);

// Streams what the job's mode writes itself in this format.
void answer_mode_written(httplib::Response& res, std::shared_ptr<const api::JobParams> job, api::VolumeSource volumes,
                         const VolumeRequest& v, const std::string& filename, Metrics& metrics);

}  // namespace voxd::server
