#include "server/cli/cli_output.h"

#include <cstdio>
#include <filesystem>

#include "voxd/error.h"

namespace voxd::cli {

std::string with_format_list(std::string usage) {
  const std::string placeholder = "{formats}";
  if (const std::size_t at = usage.find(placeholder); at != std::string::npos)
    usage.replace(at, placeholder.size(), names_joined(kVolumeFormatNames, " | ", " | "));
  return usage;
}

OutputChoice read_output_choice(const Args& args, const std::string& command) {
  OutputChoice out;
  const auto path = args.value("output");
  if (!path || path->empty()) throw UsageError(command + " needs -o OUT (see voxd " + command + " --help)");
  out.path = *path;
  if (auto f = args.value("format")) {
    const auto format = volume_format_from_string(*f);
    if (!format) throw UsageError("--format must be " + volume_format_choices() + ", got '" + *f + "'");
    out.format = *format;
  } else {
    const auto format = volume_format_from_path(out.path);
    if (!format)
      throw UsageError("cannot tell the output format from '" + out.path +
                       "'; use --format " + names_joined(kVolumeFormatNames, "|", "|"));
    out.format = *format;
  }
  if (auto p = args.value("raw-packing")) {
    if (*p == "bits") out.options.raw_packing = RawPacking::bits;
    else if (*p != "bytes") throw UsageError("--raw-packing must be bytes or bits, got '" + *p + "'");
  }
  if (auto e = args.value("nrrd-encoding")) {
    if (*e == "gzip") out.options.nrrd_encoding = NrrdEncoding::gzip;
    else if (*e != "raw") throw UsageError("--nrrd-encoding must be raw or gzip, got '" + *e + "'");
  }
  if (auto q = args.value("quantize")) {
    if (*q == "u8") out.options.quantize = Quantize::u8;
    else if (*q == "u16") out.options.quantize = Quantize::u16;
    else if (*q != "none") throw UsageError("--quantize must be none, u8 or u16, got '" + *q + "'");
  }
  return out;
}

std::uint64_t write_output(const std::string& path, const std::function<void(ByteSink&)>& encode) {
  if (path == "-") {
    struct StdoutSink final : ByteSink {
      using ByteSink::write;
      std::uint64_t n = 0;
      void write(std::span<const std::uint8_t> b) override {
        if (std::fwrite(b.data(), 1, b.size(), stdout) != b.size()) throw Error(ErrorCode::io_error, "cannot write to standard output");
        n += b.size();
      }
    } sink;
    encode(sink);
    std::fflush(stdout);
    return sink.n;
  }
  const std::string tmp = path + ".partial";
  try {
    FileSink sink(tmp);
    encode(sink);
    sink.close();
    std::filesystem::rename(tmp, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
  return std::filesystem::file_size(path);
}

}  // namespace voxd::cli
