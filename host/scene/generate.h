// Procedural scenes for scaling studies (10^3 .. 10^7 primitives) and the
// classic failure case of uniform grids.
#pragma once

#include <cstdint>
#include <string>

#include "host/scene/scene.h"

namespace cr {

// A sphereflake after SPD's balls.c (each sphere carries nine children of a
// third of its radius, six around its equator and three above) on a ground
// quad (two triangles); depth 4 has 7381 spheres, depth 7 has 5,380,840.
Scene GenerateSphereflake(int depth);

// A closed, bumpy triangle mesh of about `triangles` triangles: a sphere
// tessellated as a cube projected onto it, each face an n x n grid, radius
// modulated by a few sines.
Scene GenerateBumpySphere(std::uint64_t triangles);

// A triangle mesh refined to exactly `triangles` triangles, the same surface
// (flat subdivision: no smoothing): rounds of midpoint subdivision (each
// triangle into four, the edge midpoints computed alike from both sides, so
// no cracks) while the count stays within the target, then the largest
// triangles bisected across their longest edge (a T-junction there) until
// the count is reached. Keeps the mesh's camera, lights and materials; its
// shading normals are dropped. InputError when the mesh has other primitives
// or the target is below its triangle count or above 2^27.
Scene SubdivideMesh(const Scene& mesh, std::uint64_t triangles);

// "Teapot in a stadium" (Haines): a dense object (a sphereflake of the given
// depth, 1 unit across) at the centre of a sparse scene 10^4 units across
// (a ground plane, a ring of large pillars), the camera close to the object.
Scene GenerateStadium(int depth);

// A field of about n clipped quadrics (NFF extension `quadric`): ellipsoids,
// hyperboloids of one and two sheets, paraboloids, cylinders and cones,
// randomly tilted, one per cell of a square grid on a ground quad, the camera
// above one corner looking across (seeded: the same n gives the same scene).
Scene GenerateQuadricField(std::uint64_t n);

// A field of about n convex polyhedra (NFF extension `polyhedron`): cubes,
// octahedra, truncated octahedra and capped hexagonal prisms, randomly
// tilted, one per cell of a square grid on a ground quad (seeded), as the
// quadric field.
Scene GeneratePolyhedronField(std::uint64_t n);

// A field of about n SDF blocks (NFF extension `sdf`), one per cell: two
// balls joined by a smooth union, with a standing torus, a tilted capsule or
// a rounded slab added (seeded), marched with eps 0.001, 256 steps and
// relaxation 1.5, as the quadric field.
Scene GenerateSdfField(std::uint64_t n);

// A field of about n CSG solids (NFF extension `csg`), one per cell: a
// rounded cube with three bites, a notched lens or three crossed bars with
// a spherical bite (4 to 5 leaves, so about 4.3 n primitives; seeded), as
// the quadric field.
Scene GenerateCsgField(std::uint64_t n);

// Writes a generated scene (spheres and triangles) as NFF.
void WriteNFF(const Scene& scene, const std::string& path);

}  // namespace cr
