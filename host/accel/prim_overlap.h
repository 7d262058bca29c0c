// Does a primitive's surface meet an axis-aligned box? Exact tests in double,
// used by the grid builder to insert each primitive into the cells its shape
// (not merely its bounding box) overlaps. Callers make them conservative by
// passing a slightly enlarged box (see grid_builder.cpp).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "kernels/types.h"
#include "host/scene/scene.h"

namespace cr {

// Separating axis test (Akenine-Moller 2001, "Fast 3D triangle-box overlap
// testing"): the 3 box normals, the triangle normal and the 9 edge cross
// products. Degenerate triangles are tested against the axes that remain.
bool TriangleOverlapsBox(const Triangle& tri, const glm::dvec3& lo, const glm::dvec3& hi);

// Arvo 1990 ("A simple method for box-sphere intersection testing"), hollow
// form: the sphere's surface meets the box iff the nearest point of the box is
// inside the sphere and the farthest is not (a box wholly inside the ball
// holds no surface).
bool SphereOverlapsBox(const Sphere& s, const glm::dvec3& lo, const glm::dvec3& hi);

// Open cone or cylinder: a conservative test, tighter than the bounding box.
// The box (through its bounding sphere) must meet the slab 0 <= s <= H along
// the axis, and its centre's distance to the axis segment must lie in
// [rmin - R, rmax + R], R the box's half diagonal (distance to a segment is
// 1-Lipschitz and every surface point lies at distance r(s) from it).
bool ConeOverlapsBox(const Cone& c, const glm::dvec3& lo, const glm::dvec3& hi);

// Unified primitive g of the scene (spheres, triangles, cones) against the box;
// the caller has already checked that the box meets g's bounding box.
bool PrimOverlapsBox(const Scene& scene, std::uint32_t g, const glm::dvec3& lo, const glm::dvec3& hi);

}  // namespace cr
