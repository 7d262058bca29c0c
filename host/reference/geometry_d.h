// Double-precision geometry of the reference tracer: intersections that find
// every root, and point-to-surface distances used to adjudicate disagreements.
// Written for certainty, not speed. The primitives are the scene's float data,
// converted exactly to double.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "kernels/types.h"

namespace cr::ref {

struct DRay {
  glm::dvec3 o, d, inv;
  double tmin = 0.0, tmax = 0.0;
  int kx = 0, ky = 1, kz = 2;
  double sx = 0.0, sy = 0.0, sz = 1.0;
};

DRay MakeRay(const RayRecord& r);
DRay MakeRay(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax);

inline glm::dvec3 D3(const float* p) { return {p[0], p[1], p[2]}; }

// Every root in [tmin, tmax], ascending; returns how many (0..2). Triangles
// also return barycentrics of the first root.
int SphereRoots(const DRay& r, const Sphere& s, double t[2]);
int TriangleRoots(const DRay& r, const Triangle& tri, double t[1], double* u, double* v);
int ConeRoots(const DRay& r, const Cone& c, double t[2]);

// Distance from p to the surface.
double SphereDistance(const Sphere& s, const glm::dvec3& p);
double TriangleDistance(const Triangle& tri, const glm::dvec3& p);
double ConeDistance(const Cone& c, const glm::dvec3& p);

// Outward normal of the surface at p (unnormalised for triangles).
glm::dvec3 SphereNormal(const Sphere& s, const glm::dvec3& p);
glm::dvec3 TriangleNormal(const Triangle& tri);
glm::dvec3 ConeNormal(const Cone& c, const glm::dvec3& p);

}  // namespace cr::ref
