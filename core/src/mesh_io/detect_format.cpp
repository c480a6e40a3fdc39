// Format detection from content. Magic numbers decide Draco and PLY; the exact
// size rule (84 + 50 * count == size) decides binary STL even when its header
// starts with "solid", as many exporters write it; then the text formats are
// told apart by their first keywords, and anything else that is binary and
// long enough for an STL header is taken as binary STL so the decoder can say
// what is wrong with it. The name hint only decides when content cannot.
#include <algorithm>
#include <cstring>
#include <string>
#include <string_view>

#include "mesh_io/detect_format.h"
#include "mesh_io/text_encoding.h"
#include "mesh_io/text_lines.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd {
namespace {

constexpr std::size_t kStlHeaderBytes = 84;
constexpr std::size_t kStlRecordBytes = 50;
// Enough to see past an 80-byte STL header and a few lines of text.
constexpr std::size_t kBinarySniffBytes = 512;
// How far to look for the first OBJ statement past leading comments.
constexpr std::size_t kObjSniffBytes = 64 * 1024;
constexpr int kObjStatementsToCheck = 32;

std::string_view as_text(std::span<const std::uint8_t> data, std::size_t max_bytes) {
  return {reinterpret_cast<const char*>(data.data()), std::min(data.size(), max_bytes)};
}

bool has_extension(std::string_view name, std::string_view extension) {
  return name.size() > extension.size() &&
         mesh_io::equals_ignoring_case(name.substr(name.size() - extension.size()), extension);
}

// Control characters other than whitespace never appear in the text formats.
bool has_binary_bytes(std::string_view bytes) {
  for (char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') return true;
  }
  return false;
}

bool is_exact_size_binary_stl(std::span<const std::uint8_t> data) {
  if (data.size() < kStlHeaderBytes) return false;
  std::uint32_t count;
  std::memcpy(&count, data.data() + 80, 4);
  return kStlHeaderBytes + kStlRecordBytes * std::uint64_t{count} == data.size();
}

bool starts_with_magic_line(std::string_view text, std::string_view magic) {
  return text.starts_with(magic) && text.size() > magic.size() &&
         (text[magic.size()] == '\n' || text[magic.size()] == '\r');
}

bool starts_with_solid(std::string_view head) {
  mesh_io::TextLines lines(head);
  while (lines.next_line()) {
    const std::string_view token = lines.next_token();
    if (!token.empty()) return mesh_io::equals_ignoring_case(token, "solid");
  }
  return false;
}

bool is_obj_keyword(std::string_view token) {
  static constexpr std::string_view keywords[] = {
      "v",    "vt",   "vn",   "vp",     "f",      "l",     "p",     "o",      "g",     "s",
      "mg",   "usemtl", "mtllib", "usemap", "maplib", "cstype", "deg", "bmat", "step", "curv",
      "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "lod",
      "shadow_obj", "trace_obj", "ctech", "stech", "bevel", "c_interp", "d_interp"};
  for (std::string_view k : keywords)
    if (token == k) return true;
  return false;
}

enum class Verdict { no, undecided, yes };

// OBJ when the first statement after any comments is an OBJ keyword and a
// vertex or face follows soon. Unknown statements after the first one are
// tolerated, as the decoder ignores them (exporters add their own).
Verdict classify_obj(std::span<const std::uint8_t> data) {
  const std::string_view head = as_text(data, kObjSniffBytes);
  const bool whole_file = head.size() == data.size();
  mesh_io::TextLines lines(head);
  int statements = 0;
  while (statements < kObjStatementsToCheck && lines.next_line()) {
    // The window's last line may be cut mid-keyword.
    if (!whole_file && lines.next_line_offset() == head.size()) break;
    const std::string_view keyword = lines.next_token();
    if (keyword.empty() || keyword.starts_with('#')) continue;
    if (statements == 0 && !is_obj_keyword(keyword)) return Verdict::no;
    if (keyword == "v" || keyword == "f") return Verdict::yes;
    ++statements;
  }
  // Only comments, or only names and materials so far: could be OBJ.
  return Verdict::undecided;
}

}  // namespace

namespace mesh_io {

std::string_view foreign_format_name(std::span<const std::uint8_t> data) {
  struct Signature {
    std::string_view magic;
    std::string_view name;
  };
  static constexpr Signature signatures[] = {
      {"PK\x03\x04", "a ZIP archive (3MF files are ZIP archives)"},
      {"glTF", "binary glTF (.glb)"},
      {"Kaydara FBX Binary", "binary FBX"},
      {"\x1f\x8b", "a gzip-compressed file"},
      {"\x89PNG", "a PNG image"},
      {"\xFF\xD8\xFF", "a JPEG image"},
      {"%PDF", "a PDF document"},
  };
  const std::string_view head = as_text(data, 32);
  for (const Signature& s : signatures)
    if (head.starts_with(s.magic)) return s.name;
  return {};
}

}  // namespace mesh_io

MeshFormat detect_mesh_format(std::span<const std::uint8_t> data, std::string_view name_hint) {
  if (data.empty()) return MeshFormat::unknown;
  const std::string_view head = as_text(data, kBinarySniffBytes);
  if (head.starts_with("DRACO")) return MeshFormat::draco;
  if (starts_with_magic_line(head, "ply")) return MeshFormat::ply;
  if (is_exact_size_binary_stl(data)) return MeshFormat::stl_binary;
  // UTF-16 text: told apart by its first characters as UTF-8.
  if (const auto order = mesh_io::utf16_byte_order(data)) {
    std::size_t sniff = std::min(data.size() & ~std::size_t{1}, 2 * kObjSniffBytes);
    // Not half a surrogate pair at the window's end.
    const std::size_t last = sniff - 2;
    const unsigned lead = *order == mesh_io::Utf16Order::big_endian ? data[last] : data[last + 1];
    if (sniff < data.size() && lead >= 0xD8 && lead <= 0xDB) sniff -= 2;
    try {
      const std::string text = mesh_io::utf16_to_utf8(data.first(sniff), *order);
      if (text.empty()) return MeshFormat::unknown;
      return detect_mesh_format({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}, name_hint);
    } catch (const Error&) {
      return MeshFormat::unknown;  // a broken surrogate: decode_mesh says where
    }
  }
  // Well-known other formats would otherwise pass for a broken binary STL.
  if (!mesh_io::foreign_format_name(data).empty()) return MeshFormat::unknown;
  if (has_binary_bytes(head)) {
    return data.size() >= kStlHeaderBytes ? MeshFormat::stl_binary : MeshFormat::unknown;
  }
  if (starts_with_solid(head)) return MeshFormat::stl_ascii;
  switch (classify_obj(data)) {
    case Verdict::yes: return MeshFormat::obj;
    case Verdict::undecided: return has_extension(name_hint, ".obj") ? MeshFormat::obj : MeshFormat::unknown;
    case Verdict::no: break;
  }
  return MeshFormat::unknown;
}

}  // namespace voxd
