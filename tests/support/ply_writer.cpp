#include "support/ply_writer.h"

#include <bit>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace voxd::test {
namespace {

class PlyBody {
 public:
  explicit PlyBody(PlyOptions::Encoding encoding) : encoding_(encoding) {}

  // Writes `value` as the named PLY type.
  void put(const std::string& type, double value) {
    if (encoding_ == PlyOptions::Encoding::ascii) {
      if (type == "float" || type == "double") text_ << value;
      else text_ << static_cast<long long>(value);
      text_ << ' ';
      return;
    }
    if (type == "char") put_bits(static_cast<std::int8_t>(value));
    else if (type == "uchar") put_bits(static_cast<std::uint8_t>(value));
    else if (type == "short") put_bits(static_cast<std::int16_t>(value));
    else if (type == "ushort") put_bits(static_cast<std::uint16_t>(value));
    else if (type == "int") put_bits(static_cast<std::int32_t>(value));
    else if (type == "uint") put_bits(static_cast<std::uint32_t>(value));
    else if (type == "float") put_bits(static_cast<float>(value));
    else if (type == "double") put_bits(value);
    else throw std::invalid_argument("unknown PLY type " + type);
  }

  void end_element() {
    if (encoding_ == PlyOptions::Encoding::ascii) text_ << '\n';
  }

  std::vector<std::uint8_t> bytes() const {
    if (encoding_ != PlyOptions::Encoding::ascii) return binary_;
    const std::string s = text_.str();
    return {s.begin(), s.end()};
  }

  std::ostringstream text_;

 private:
  template <typename T>
  void put_bits(T value) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    const bool big = encoding_ == PlyOptions::Encoding::binary_big_endian;
    for (std::size_t i = 0; i < sizeof(T); ++i) binary_.push_back(b[big ? sizeof(T) - 1 - i : i]);
  }

  PlyOptions::Encoding encoding_;
  std::vector<std::uint8_t> binary_;
};

}  // namespace

std::vector<std::uint8_t> to_ply(const Mesh& mesh, const PlyOptions& o) {
  std::vector<std::vector<std::uint32_t>> faces;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& a = mesh.triangles[t];
    if (o.quads && t + 1 < mesh.triangles.size()) {
      const auto& b = mesh.triangles[t + 1];
      if (b[0] == a[0] && b[1] == a[2]) {
        faces.push_back({a[0], a[1], a[2], b[2]});
        ++t;
        continue;
      }
    }
    faces.push_back({a[0], a[1], a[2]});
  }

  std::ostringstream header;
  const char* encodings[] = {"ascii", "binary_little_endian", "binary_big_endian"};
  header << "ply\nformat " << encodings[static_cast<int>(o.encoding)] << " 1.0\ncomment voxd test\n";
  header << "element vertex " << mesh.vertices.size() << '\n';
  if (o.extra_properties) header << "property uchar quality\n";
  header << "property " << o.coordinate_type << " x\nproperty " << o.coordinate_type << " y\n";
  if (o.extra_properties) header << "property float confidence\n";
  header << "property " << o.coordinate_type << " z\n";
  if (o.extra_properties) header << "element material 2\nproperty list uchar int ids\nproperty double shine\n";
  header << "element face " << faces.size() << '\n';
  if (o.extra_properties) header << "property list uchar float texcoord\n";
  header << "property list " << o.count_type << ' ' << o.index_type << ' ' << o.index_name << '\n';
  if (o.extra_properties) header << "property int flags\n";
  header << "end_header\n";

  PlyBody body(o.encoding);
  body.text_.precision(17);
  for (const auto& v : mesh.vertices) {
    if (o.extra_properties) body.put("uchar", 7);
    body.put(o.coordinate_type, v.x);
    body.put(o.coordinate_type, v.y);
    if (o.extra_properties) body.put("float", 0.5);
    body.put(o.coordinate_type, v.z);
    body.end_element();
  }
  if (o.extra_properties) {
    for (int m = 0; m < 2; ++m) {
      body.put("uchar", 2);
      body.put("int", m);
      body.put("int", -m);
      body.put("double", 1.5);
      body.end_element();
    }
  }
  for (const auto& f : faces) {
    if (o.extra_properties) {
      body.put("uchar", 2);
      body.put("float", 0.25);
      body.put("float", 0.75);
    }
    body.put(o.count_type, static_cast<double>(f.size()));
    for (auto i : f) body.put(o.index_type, i);
    if (o.extra_properties) body.put("int", -1);
    body.end_element();
  }
  const std::string head = header.str();
  std::vector<std::uint8_t> out(head.begin(), head.end());
  const auto data = body.bytes();
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

}  // namespace voxd::test
