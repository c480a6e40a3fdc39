#pragma once
// A slice function's options (voxd/voxelize/slice_functions.h) as JSON: the
// job JSON's `slice` object with mode `slice`, and the `slice` field of a
// section or preview coloured by a slice function on a finished job
// (colour=slice), so the colours shown while a parameter is edited and the
// volume a slice job then makes read the same object.
#include <string>

#include <nlohmann/json.hpp>

#include "api/param_validator.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::api {

// The name of a slice function's object: the job JSON's key with mode
// slice, and a section's or preview's colour value and field (colour=slice
// and slice=...). Spelled here only, as the mode's own name is spelled in
// its own files.
inline constexpr const char* kSliceName = "slice";

// Reads the object `d` into `out` (which holds the defaults); every problem
// goes to `val` at path + "/" + field, e.g. "/slice/period".
void parse_slice_options(ParamValidator& val, const nlohmann::json& d, const std::string& path, SliceOptions& out);

// The options of out.function as the object parse_slice_options reads back
// to the same options: "function", "axis", then that function's fields
// only, defaults included, colours as "#rrggbbaa". Keys in nlohmann's
// (sorted) order, so its dump() is canonical: a key for the result.
nlohmann::json slice_options_json(const SliceOptions& options);

}  // namespace voxd::api
