#pragma once
// Where a command's volume goes: -o OUT (or - for standard output), its
// format (--format, else OUT's extension) and encoding flags, and writing it
// so that OUT is never half written. Shared by `voxd voxelize` and `voxd
// submit`, which take the same output flags.
#include <cstdint>
#include <functional>
#include <string>

#include "server/cli/cli_args.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"

namespace voxd::cli {

// The output flags, each taking a value.
inline const char* const kOutputFlags[] = {"output", "format", "raw-packing", "nrrd-encoding", "quantize"};

struct OutputChoice {
  std::string path;  // "-" for standard output
  VolumeFormat format = VolumeFormat::rle;
  EncodeOptions options;
};

// Reads -o, --format, --raw-packing, --nrrd-encoding and --quantize;
// UsageError naming the command when they are missing or wrong.
OutputChoice read_output_choice(const Args& args, const std::string& command);

// A usage text with its "{formats}" replaced by the volume formats,
// "rle | binvox | ..." (voxd/encode/volume_format.h's table).
std::string with_format_list(std::string usage);

// Runs `encode` into OUT's temporary file and renames it into place (or
// into standard output for "-"); the bytes written.
std::uint64_t write_output(const std::string& path, const std::function<void(ByteSink&)>& encode);

}  // namespace voxd::cli
