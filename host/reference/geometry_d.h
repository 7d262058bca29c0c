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
  // Time in the shutter interval (motion blur): a moving piece meets the ray
  // shifted into its rest frame (ReferenceTracer::PieceRay). shift: the
  // largest component of the shift that made this ray (0 for a ray in the
  // world frame), which check's tolerance adds to |o| (a float tracer rounds
  // the shifted origin at that scale).
  double time = 0.0;
  double shift = 0.0;
};

DRay MakeRay(const RayRecord& r);
DRay MakeRay(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax);

inline glm::dvec3 D3(const float* p) { return {p[0], p[1], p[2]}; }

// Real roots of a t^2 + 2 bh t + c = 0 with discriminant disc = bh^2 - a c
// (computed by the caller without cancellation), ascending, stable (Press et
// al.); returns 0 or 2.
int Quadratic(double a, double bh, double c, double disc, double t[2]);
// Keeps the roots in [tmin, tmax], in order; returns how many.
int KeepInRange(double t[2], int n, double tmin, double tmax);
// Parameter s in [0, 1] of the point of segment p1 + s (q1 - p1) closest to
// segment p2 q2 (Ericson, Real-Time Collision Detection 5.1.9).
double ClosestOnSegment(const glm::dvec3& p1, const glm::dvec3& q1, const glm::dvec3& p2, const glm::dvec3& q2);
// A ball around points pts[0..n) thickened by rad: centre the mean of the
// points, radius the largest distance to one plus rad.
void BallOf(const glm::dvec3* pts, int n, double rad, glm::dvec3& mid, double& reach);

// The primitives' own roots, distances and normals are their host
// functions (host/prims/prim_host.h: RefRoots, RefDistance, RefNormal).

}  // namespace cr::ref
