#pragma once
// Rigid rotations applied to the mesh before voxelization, about the model
// origin (0,0,0), so explicit grids keep their meaning in the rotated frame.
#include <glm/mat3x3.hpp>

#include "voxd/mesh.h"

namespace voxd {

// Rotation by `angle_deg` degrees about `axis` (need not be unit length).
glm::dmat3 rotation_from_axis_angle(glm::dvec3 axis, double angle_deg);
// Rotation from a quaternion (w, x, y, z); normalised first.
glm::dmat3 rotation_from_quaternion(double w, double x, double y, double z);

// Patil & Ravi: cast rays along the smallest extent. Returns the axis
// permutation (a proper rotation, det +1) that puts the smallest extent of
// `bounds` on x, the axis the engine's parity rays run along.
glm::dmat3 auto_orient_rotation(const Aabb& bounds);

void rotate_mesh(Mesh& mesh, const glm::dmat3& rotation);

// Bounds the mesh would have after rotate_mesh (float rounding included),
// without modifying it.
Aabb rotated_bounds(const Mesh& mesh, const glm::dmat3& rotation);

}  // namespace voxd
