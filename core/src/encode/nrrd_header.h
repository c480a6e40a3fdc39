#pragma once
// The NRRD text header (nrrd.cpp), shared with the streamed writer.
#include <string>
#include <string_view>

#include "voxd/encode/volume_format.h"

namespace voxd::encode {

std::string nrrd_header(const Grid& g, const char* type, std::string_view content, NrrdEncoding encoding);

}  // namespace voxd::encode
