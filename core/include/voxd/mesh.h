#pragma once
// Indexed triangle mesh, the engine's input type. Decoders of triangle-soup
// formats (STL) emit three vertices per triangle; weld_vertices() merges them
// when topology is needed (the mesh report, winding numbers). The voxelizers do
// not need welding: they quantize each vertex identically wherever it appears.
#include <array>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

namespace voxd {

struct Aabb {
  glm::dvec3 min{0.0};
  glm::dvec3 max{0.0};
  glm::dvec3 extent() const { return max - min; }
  glm::dvec3 center() const { return (min + max) * 0.5; }
};

// Memory for mesh arrays: large ones straight from the OS on transparent
// huge pages where the kernel allows them (a 1.1M-triangle STL is 53 MB of
// vertices and indices: 13 thousand page faults on 4 KiB pages, 27 on 2 MiB
// ones), small ones from the heap.
void* allocate_mesh_memory(std::size_t bytes);
void free_mesh_memory(void* p, std::size_t bytes) noexcept;

// An allocator over allocate_mesh_memory whose resize() leaves new elements
// default-initialized, which for glm vectors and index arrays means not
// written at all: a decoder that writes every element does not clear the
// memory first, and its threads fault the fresh pages in side by side
// instead of one thread clearing them all.
template <class T>
struct DefaultInitAllocator {
  using value_type = T;
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocate_mesh_memory(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { free_mesh_memory(p, n * sizeof(T)); }
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    std::construct_at(p, std::forward<Args>(args)...);
  }
};

template <class T, class U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
  return true;
}

using VertexArray = std::vector<glm::vec3, DefaultInitAllocator<glm::vec3>>;
using TriangleArray = std::vector<std::array<std::uint32_t, 3>, DefaultInitAllocator<std::array<std::uint32_t, 3>>>;

struct Mesh {
  VertexArray vertices;
  TriangleArray triangles;

  std::size_t triangle_count() const { return triangles.size(); }
  glm::vec3 corner(std::size_t tri, int c) const { return vertices[triangles[tri][c]]; }
};

// Bounding box of the vertices referenced by triangles. Empty mesh -> zero box.
Aabb bounds(const Mesh& mesh);

}  // namespace voxd
