#include "server/http/volume_request.h"

#include <algorithm>
#include <stdexcept>

#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/voxelize/streamed.h"

#include "api/result_json.h"
#include "server/http/problem.h"
#include "server/http/volume_stream.h"
#include "server/jobs/job_store.h"

namespace voxd::server {
namespace {

ProblemError invalid_query(const std::string& detail) {
  return ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", detail));
}

void refuse_quantized_bits(const VolumeRequest& v) {
  if (v.options.quantize != Quantize::none)
    throw invalid_query("quantize applies to float values (a volume of type f32); this volume is bits");
}

}  // namespace

VolumeRequest read_volume_request(const httplib::Request& req) {
  VolumeRequest v;
  v.gzip = req.get_header_value("Accept-Encoding").find("gzip") != std::string::npos;
  if (req.has_param("format")) {
    const auto f = volume_format_from_string(req.get_param_value("format"));
    if (!f)
      throw invalid_query("format must be " + volume_format_choices() + ", got '" +
                          req.get_param_value("format") + "'");
    v.format = *f;
  }
  if (req.has_param("quantize")) {
    const std::string q = req.get_param_value("quantize");
    if (q == "u8") v.options.quantize = Quantize::u8;
    else if (q == "u16") v.options.quantize = Quantize::u16;
    else if (q != "none")
      throw invalid_query("quantize must be none, u8 or u16, got '" + q + "'");
  }
  if (req.has_param("encoding")) {
    const std::string e = req.get_param_value("encoding");
    if (v.format != VolumeFormat::nrrd)
      throw invalid_query("encoding applies to format nrrd only (for compression in transit send Accept-Encoding: gzip)");
    if (e == "gzip") v.options.nrrd_encoding = NrrdEncoding::gzip;
    else if (e != "raw")
      throw invalid_query("encoding must be raw or gzip, got '" + e + "'");
  }
  if (req.has_param("packing")) {
    const std::string p = req.get_param_value("packing");
    if (p == "bits") v.options.raw_packing = RawPacking::bits;
    else if (p != "bytes")
      throw invalid_query("packing must be bytes or bits, got '" + p + "'");
  }
  return v;
}

std::string volume_content(const JobSnapshot& job, const std::string& layer) {
  if (!layer.empty()) return job.job->mode->layer_content(layer, job.values);
  return api::volume_content(job.has_value_volume() ? job.values : nlohmann::json());
}

void check_format_holds(const api::JobParams& params, const VolumeRequest& v) {
  if (!params.mode->writes(v.format) && !params.has_values()) refuse_quantized_bits(v);
  if (auto refusal = params.format_refusal(v.format, v.options)) throw invalid_query(*refusal);
}

void check_bits_format(const VolumeRequest& v) {
  refuse_quantized_bits(v);
  if (auto refusal = format_refusal(BitVolume(), v.format)) throw invalid_query(*refusal);
}

void answer_values(httplib::Response& res, std::shared_ptr<const ValueVolume> values, const VolumeRequest& v,
                   const std::string& filename, Metrics& metrics) {
  if (auto refusal = format_refusal(*values, v.format, v.options)) throw invalid_query(*refusal);
  res.set_header("X-Voxd-Value-Type", value_type_name(*values));
  stream_volume(res, std::move(values), v.format, v.options, v.gzip, filename, &metrics);
}

void answer_bits(httplib::Response& res, std::shared_ptr<const BitVolume> bits, const VolumeRequest& v,
                 const std::string& filename, Metrics& metrics) {
  res.set_header("X-Voxd-Value-Type", "bit");
  stream_volume(res, std::move(bits), v.format, v.options, v.gzip, filename, &metrics);
}

namespace {

// The stored RLE as it is, in 1 MiB pieces.
void send_stored(const StoredBlob& stored, ByteSink& sink) {
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  const auto source = stored.open();
  std::vector<std::uint8_t> buffer(std::min<std::uint64_t>(kChunk, std::max<std::uint64_t>(stored.size(), 1)));
  while (const std::size_t n = source->read(buffer.data(), buffer.size())) sink.write(std::span(buffer).first(n));
}

}  // namespace

void answer_stored_bits(httplib::Response& res, std::shared_ptr<const StoredBlob> rle, const VolumeRequest& v,
                        const std::string& filename, Metrics& metrics) {
  if (auto refusal = streaming_refusal(v.format)) throw std::logic_error(*refusal);
  res.set_header("X-Voxd-Value-Type", "bit");
  stream_encoded(
      res, media_type(v.format),
      [rle = std::move(rle), v](ByteSink& sink) {
        if (v.format == VolumeFormat::rle) return send_stored(*rle, sink);
        const Grid grid = read_rle_bit_grid(*rle->open());
        BitSlabWriter writer(grid, v.format, v.options, sink);
        read_rle_bit_slabs(*rle->open(), replay_bit_slab_layers(grid),
                           [&](std::int64_t k0, const BitVolume& slab) { writer.write(k0, slab); }, kStoredSlabLimits);
        writer.finish();
      },
      v.gzip, filename, &metrics);
}

void answer_stored_values(httplib::Response& res, std::shared_ptr<const StoredBlob> rle, const Grid& grid,
                          const ValueVolume& type, const VolumeRequest& v, const std::string& filename, Metrics& metrics) {
  if (auto refusal = streaming_refusal(type, v.format, v.options)) throw std::logic_error(*refusal);
  res.set_header("X-Voxd-Value-Type", value_type_name(type));
  stream_encoded(
      res, media_type(v.format),
      [rle = std::move(rle), grid, type, v](ByteSink& sink) {
        if (v.format == VolumeFormat::rle) return send_stored(*rle, sink);
        ValueSlabWriter writer(grid, type, v.format, v.options, sink);
        read_rle_value_slabs(*rle->open(), replay_value_slab_layers(grid),
                             [&](std::int64_t k0, const ValueVolume& slab) { writer.write(k0, slab); }, kStoredSlabLimits);
        writer.finish();
      },
      v.gzip, filename, &metrics);
}

void answer_mode_written(httplib::Response& res, std::shared_ptr<const api::JobParams> job, api::VolumeSource volumes,
                         const VolumeRequest& v, const std::string& filename, Metrics& metrics) {
  stream_encoded(
      res, media_type(v.format),
      [volumes = std::move(volumes), job = std::move(job), format = v.format](ByteSink& sink) {
        job->mode->write(format, *job, volumes, sink);
      },
      v.gzip, filename, &metrics);
}

}  // namespace voxd::server
