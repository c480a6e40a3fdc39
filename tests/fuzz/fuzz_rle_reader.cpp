// libFuzzer harness for the RLE reader, every value type: a lying header or
// runs past the grid must be an Error, never an allocation or a read past
// the input.
#include <cstdint>
#include <span>

#include "voxd/error.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  voxd::ReadLimits limits;
  limits.max_volume_bytes = std::uint64_t{64} << 20;
  try { (void)voxd::read_rle_bits(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_u8(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_u16(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_f32(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_rgba8(bytes, limits); } catch (const voxd::Error&) {}
  try { (void)voxd::read_rle_metadata(bytes); } catch (const voxd::Error&) {}
  try {
    std::uint64_t filled = 0;
    voxd::read_rle_bit_slabs(bytes, 3, [&](std::int64_t, const voxd::BitVolume& slab) { filled += slab.count(); }, limits);
  } catch (const voxd::Error&) {
  }
  try {
    std::uint64_t layers = 0;
    voxd::read_rle_value_slabs(bytes, 2, [&](std::int64_t, const voxd::ValueVolume& slab) { layers += voxd::grid_of(slab).dims.z; },
                               limits);
  } catch (const voxd::Error&) {
  }
  return 0;
}
