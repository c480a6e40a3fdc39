// Palette elements: the built-in palettes, complements, validation. See
// voxd/voxelize/palette.h.
#include <array>
#include <cmath>
#include <set>
#include <string>

#include "voxd/error.h"
#include "voxd/voxelize/palette.h"

namespace voxd {
namespace {

const char kAxisName[3] = {'x', 'y', 'z'};

// The term of coordinate `axis` measured from the face at `side` (0: the
// face axis = 0, 1: the face axis = 1), as a linear form c . p + constant:
// side 0 gives p_axis, side 1 gives 1 - p_axis.
struct Term {
  glm::dvec3 c{0.0};
  double constant = 0.0;
};
Term from_face(int axis, int side) {
  Term t;
  t.c[axis] = side == 0 ? 1.0 : -1.0;
  t.constant = side == 0 ? 0.0 : 1.0;
  return t;
}

// sum(terms) <= bound as a half-space.
HalfSpace sum_at_most(std::initializer_list<Term> terms, double bound) {
  HalfSpace h;
  h.offset = bound;
  for (const Term& t : terms) {
    h.normal += t.c;
    h.offset -= t.constant;
  }
  return h;
}

std::string corner_name(int a, int sa, int b, int sb) {
  return std::string{kAxisName[a]} + std::to_string(sa) + kAxisName[b] + std::to_string(sb);
}

PaletteElement single_piece(std::string name, ConvexPiece piece) {
  PaletteElement e;
  e.name = std::move(name);
  e.pieces.push_back(std::move(piece));
  return e;
}

// The 8 corner tetrahedra X + Y + Z <= 1 (X measured from the corner's face).
void add_tetrahedra(std::vector<PaletteElement>& out) {
  for (int cz = 0; cz < 2; ++cz)
    for (int cy = 0; cy < 2; ++cy)
      for (int cx = 0; cx < 2; ++cx)
        out.push_back(single_piece("tetra-x" + std::to_string(cx) + "y" + std::to_string(cy) + "z" + std::to_string(cz),
                                   {sum_at_most({from_face(0, cx), from_face(1, cy), from_face(2, cz)}, 1.0)}));
}

// The 12 wedges U + V <= 1: the half voxel on the side of the edge along
// `axis` at corner (cu, cv) of the two other axes.
void add_wedges(std::vector<PaletteElement>& out) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int a = std::min(u, v), b = std::max(u, v);
    for (int cb = 0; cb < 2; ++cb)
      for (int ca = 0; ca < 2; ++ca)
        out.push_back(single_piece(std::string("wedge-") + kAxisName[axis] + "-" + corner_name(a, ca, b, cb),
                                   {sum_at_most({from_face(a, ca), from_face(b, cb)}, 1.0)}));
  }
}

// The 24 corner pyramids: the square base on face (axis, side), the apex
// over corner (ca, cb) of the opposite face: A + H <= 1 and B + H <= 1, H
// the height above the base.
void add_pyramids(std::vector<PaletteElement>& out) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int a = std::min(u, v), b = std::max(u, v);
      const Term h = from_face(axis, side);
      for (int cb = 0; cb < 2; ++cb)
        for (int ca = 0; ca < 2; ++ca)
          out.push_back(single_piece(std::string("pyramid-") + kAxisName[axis] + std::to_string(side) + "-" +
                                         corner_name(a, ca, b, cb),
                                     {sum_at_most({from_face(a, ca), h}, 1.0), sum_at_most({from_face(b, cb), h}, 1.0)}));
    }
}

bool finite(const HalfSpace& h) {
  return std::isfinite(h.normal.x) && std::isfinite(h.normal.y) && std::isfinite(h.normal.z) && std::isfinite(h.offset);
}

}  // namespace

bool PaletteElement::contains(const glm::dvec3& p) const {
  for (const ConvexPiece& piece : pieces) {
    bool in = true;
    for (const HalfSpace& h : piece) in = in && h.contains(p);
    if (in) return true;
  }
  return false;
}

std::optional<std::size_t> Palette::find(std::string_view name) const {
  for (std::size_t i = 0; i < elements.size(); ++i)
    if (elements[i].name == name) return i;
  return std::nullopt;
}

PaletteElement complement_of(const PaletteElement& element, std::string name) {
  // The complement of a union is the intersection of the pieces'
  // complements; each of those is a union of disjoint convex pieces, so the
  // result distributes into a union of intersections.
  std::vector<ConvexPiece> result{ConvexPiece{}};  // the full voxel
  for (const ConvexPiece& piece : element.pieces) {
    std::vector<ConvexPiece> piece_complement;
    for (std::size_t i = 0; i < piece.size(); ++i) {
      ConvexPiece part(piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(i));
      part.push_back({-piece[i].normal, -piece[i].offset});
      piece_complement.push_back(std::move(part));
    }
    std::vector<ConvexPiece> next;
    for (const ConvexPiece& r : result)
      for (const ConvexPiece& c : piece_complement) {
        ConvexPiece both = r;
        both.insert(both.end(), c.begin(), c.end());
        if (both.size() > kMaxHalfSpaces)
          throw Error(ErrorCode::invalid_argument, "the complement of palette element '" + element.name +
                                                       "' needs more than " + std::to_string(kMaxHalfSpaces) +
                                                       " half-spaces in a piece");
        next.push_back(std::move(both));
      }
    if (next.size() > kMaxPieces)
      throw Error(ErrorCode::invalid_argument, "the complement of palette element '" + element.name +
                                                   "' needs more than " + std::to_string(kMaxPieces) + " pieces");
    result = std::move(next);
  }
  PaletteElement out;
  out.name = std::move(name);
  out.pieces = std::move(result);
  return out;
}

Palette builtin_palette(int size) {
  if (size != 2 && size != 10 && size != 46 && size != 78)
    throw Error(ErrorCode::invalid_argument,
                "built-in palettes have 2, 10, 46 or 78 elements, not " + std::to_string(size));
  Palette palette;
  auto& e = palette.elements;
  e.push_back(PaletteElement{"empty", {}});
  e.push_back(PaletteElement{"full", {ConvexPiece{}}});
  if (size >= 10) add_tetrahedra(e);
  if (size >= 46) {
    add_wedges(e);
    add_pyramids(e);
  }
  if (size == 78) {
    // New complements only: a wedge's complement is another wedge.
    const std::size_t n = e.size();
    for (std::size_t i = 0; i < n; ++i)
      if (e[i].name.starts_with("tetra-") || e[i].name.starts_with("pyramid-"))
        e.push_back(complement_of(e[i], "not-" + e[i].name));
  }
  return palette;
}

void validate(const Palette& palette) {
  if (palette.elements.empty()) throw Error(ErrorCode::invalid_argument, "a palette needs at least one element");
  if (palette.elements.size() > kMaxPaletteElements)
    throw Error(ErrorCode::invalid_argument, "a palette has at most " + std::to_string(kMaxPaletteElements) +
                                                 " elements (indices are bytes), not " +
                                                 std::to_string(palette.elements.size()));
  std::set<std::string> names;
  for (std::size_t i = 0; i < palette.elements.size(); ++i) {
    const PaletteElement& e = palette.elements[i];
    const std::string which = "palette element " + std::to_string(i) + (e.name.empty() ? "" : " ('" + e.name + "')");
    if (e.name.empty()) throw Error(ErrorCode::invalid_argument, which + " needs a name");
    if (!names.insert(e.name).second) throw Error(ErrorCode::invalid_argument, which + ": the name is used twice");
    if (e.pieces.size() > kMaxPieces)
      throw Error(ErrorCode::invalid_argument, which + " has more than " + std::to_string(kMaxPieces) + " pieces");
    for (const ConvexPiece& piece : e.pieces) {
      if (piece.size() > kMaxHalfSpaces)
        throw Error(ErrorCode::invalid_argument,
                    which + " has a piece with more than " + std::to_string(kMaxHalfSpaces) + " half-spaces");
      for (const HalfSpace& h : piece) {
        if (!finite(h)) throw Error(ErrorCode::invalid_argument, which + " has a half-space with a non-finite number");
        if (h.normal == glm::dvec3(0.0))
          throw Error(ErrorCode::invalid_argument, which + " has a half-space with a zero normal");
      }
    }
  }
}

}  // namespace voxd
