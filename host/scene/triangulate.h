// Triangulation of planar polygons by ear clipping (after Eberly, "Triangulation
// by Ear Clipping"), for NFF `p`/`pp` and OBJ faces with more than 3 vertices.
// The gear faces of gears.nff are non-convex 144-gons.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace cr {

struct Triangulation {
  std::vector<std::array<std::uint32_t, 3>> triangles;  // indices into the input
  bool degenerate = false;  // fewer than 3 distinct vertices or zero area
  bool nonSimple = false;   // no ear found somewhere, or areas do not add up
  double area = 0.0;        // area of the polygon (Newell)
};

// Triangulates the polygon with vertices `pts` (in order, implicitly closed).
// Triangles keep the polygon's orientation; a triangle input comes back as
// {0, 1, 2} unchanged. Vertices are projected on the plane of the dominant
// axis of the Newell normal; repeated and collinear vertices are dropped.
Triangulation TriangulatePolygon(const std::vector<glm::dvec3>& pts);

}  // namespace cr
