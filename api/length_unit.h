#pragma once
// The unit a mesh file's coordinates are in ("units" in the job JSON). voxd
// works in millimetres: a mesh in another unit is scaled once, when it is
// read, so the grid, the analyses' parameters, the reports and the outputs'
// origins and spacings are all in millimetres.
#include "voxd/enum_names.h"

namespace voxd::api {

enum class LengthUnit { mm, cm, m, in, ft };
inline constexpr EnumNames<LengthUnit, 5> kLengthUnitNames{{{LengthUnit::mm, "mm"},
                                                            {LengthUnit::cm, "cm"},
                                                            {LengthUnit::m, "m"},
                                                            {LengthUnit::in, "in"},
                                                            {LengthUnit::ft, "ft"}}};
inline const char* to_string(LengthUnit u) noexcept { return name_of(kLengthUnitNames, u); }

// Millimetres in one unit.
inline constexpr double millimetres_per(LengthUnit u) noexcept {
  switch (u) {
    case LengthUnit::mm: return 1.0;
    case LengthUnit::cm: return 10.0;
    case LengthUnit::m: return 1000.0;
    case LengthUnit::in: return 25.4;
    case LengthUnit::ft: return 304.8;
  }
  return 1.0;
}

}  // namespace voxd::api
