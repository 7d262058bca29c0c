// The host side of the primitive types: what every type of CR_PRIM_TYPES
// (kernels/types.h) provides, declared here once for all of them and defined
// by each type in its own file, host/prims/<type>.cpp. Generic code reaches
// a type's function by overload: Scene::Visit(g, f) hands f the piece as its
// own type, and f calls, say, OverlapsBox(piece, lo, hi).
//
// Why a list of overloads and not a class hierarchy or a traits template:
// the device side has only the preprocessor (OpenCL C), so the list of
// types is an X-macro there; the same X-macro declares the host functions
// below, a type missing one fails to link with its name, and no host code
// needs a virtual call or a `switch` over the types.
//
// Adding a type: its layout and CR_PRIM_TYPES entry in kernels/types.h, its
// device test in kernels/<type>.h, its SIMD form (simd/), and these
// functions in host/prims/<type>.cpp (docs/ARCHITECTURE.md has the list).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "host/reference/geometry_d.h"
#include "host/scene/scene.h"

namespace cr {

class NffStatement;  // host/scene/nff.h

// A hit's point reprojected onto the surface (host/scene/surface.h).
struct LocalSurface {
  glm::dvec3 p{0.0};   // on the surface
  glm::dvec3 ng{0.0};  // outward geometric normal, unit
  glm::dvec3 ns{0.0};  // shading normal, unit (ng unless the type interpolates one)
};

// Per type T:
//  PrimTypeName   its name in messages and JSON ("sphere");
//  FloatBounds    its float box, rounded outward (builders, Embree boxes);
//  OverlapsBox    does its surface meet the box? exact or conservative, in
//                 double (insertion into cells and octants);
//  SplitBounds    its part inside `box` cut by the plane x[axis] = pos:
//                 float boxes of the two sides, rounded outward, each within
//                 box (the BVH's spatial splits; a side it does not reach:
//                 empty);
//  Scale          largest magnitude of its defining points (radii added):
//                 the scale of a float intersector's rounding on it;
//  SurfaceAt      the hit point near pApprox (with the hit's u, v) on its
//                 surface, in double, and its normals;
//  RefBounds      double box, rounded outward (the reference's BVH);
//  RefRoots       every root in [tmin, tmax], ascending (u, v of the first
//                 where the type reports them), in double;
//  RefDistance    distance from x to its surface; RefNormal: outward normal
//                 at x (unit);
//  RefBall        a ball around it (check's near-miss search), and
//  RefNearTimes   the ray parameters in [t0, t1] where the ray comes closest
//                 to it (check.cpp NearRay);
//  ParseNff       reads its NFF statement if `st` is one (returns false if
//                 not), adding the piece(s) and the PrimInfo to the scene.
#define CR_PRIM_HOST_DECLS_(T, U, a)                                                                             \
  const char* PrimTypeName(PrimTag<T>);                                                                          \
  Bounds FloatBounds(const T& p);                                                                                \
  bool OverlapsBox(const T& p, const glm::dvec3& lo, const glm::dvec3& hi);                                     \
  void SplitBounds(const T& p, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right);            \
  double Scale(const T& p);                                                                                      \
  LocalSurface SurfaceAt(const Scene& scene, const T& p, std::uint32_t local, const glm::dvec3& pApprox, double u, \
                         double v);                                                                              \
  void RefBounds(const T& p, glm::dvec3& lo, glm::dvec3& hi);                                                    \
  int RefRoots(const ref::DRay& r, const T& p, double t[2], double* u, double* v);                               \
  double RefDistance(const T& p, const glm::dvec3& x);                                                           \
  glm::dvec3 RefNormal(const T& p, const glm::dvec3& x);                                                         \
  void RefBall(const T& p, glm::dvec3& mid, double& reach);                                                      \
  void RefNearTimes(const T& p, const ref::DRay& r, double t0, double t1, std::vector<double>& ts);             \
  bool ParseNff(PrimTag<T>, NffStatement& st, Scene& scene);
CR_PRIM_TYPES(CR_PRIM_HOST_DECLS_)
#undef CR_PRIM_HOST_DECLS_

// HitSlack: how far from its surface a hit on the type may lie by the
// type's own definition, beyond check's tolerance (docs/TOLERANCE.md): an
// SDF block's hit threshold (its hits are where the distance falls below
// eps); 0 for the exact types.
template <class T>
double HitSlack(const T&)
{
  return 0.0;
}
double HitSlack(const Sdf& s);

// A part of a piece (PrimInfo::part: a CSG solid's leaf) as check judges
// it: the roots in [tmin, tmax] where that part bounds the piece, and the
// distance from x to the piece's surface there; for a whole piece, RefRoots
// and RefDistance.
template <class T>
int RefPartRoots(const ref::DRay& r, const T& p, std::uint32_t, double t[2])
{
  return RefRoots(r, p, t, nullptr, nullptr);
}
template <class T>
double RefPartDistance(const T& p, std::uint32_t, const glm::dvec3& x)
{
  return RefDistance(p, x);
}
int RefPartRoots(const ref::DRay& r, const Csg& c, std::uint32_t part, double t[2]);
double RefPartDistance(const Csg& c, std::uint32_t part, const glm::dvec3& x);

// The types whose record holds its float box as lo[3], hi[3] (box,
// polyhedron, SDF block, CSG solid) share these: that box as Bounds and in double, the
// ball around it, and whether a cell meets it.
template <class T>
Bounds StoredBounds(const T& p)
{
  Bounds b;
  b.lo = glm::vec3(p.lo[0], p.lo[1], p.lo[2]);
  b.hi = glm::vec3(p.hi[0], p.hi[1], p.hi[2]);
  return b;
}
template <class T>
void StoredRefBounds(const T& p, glm::dvec3& lo, glm::dvec3& hi)
{
  lo = ref::D3(p.lo);
  hi = ref::D3(p.hi);
}
template <class T>
void StoredRefBall(const T& p, glm::dvec3& mid, double& reach)
{
  const glm::dvec3 pts[2] = {ref::D3(p.lo), ref::D3(p.hi)};
  ref::BallOf(pts, 2, 0.0, mid, reach);
}
template <class T>
bool StoredBoundsMeet(const T& p, const glm::dvec3& lo, const glm::dvec3& hi)
{
  for (int a = 0; a < 3; ++a)
    if (lo[a] > double(p.hi[a]) || hi[a] < double(p.lo[a])) return false;
  return true;
}

// a and b's common part (empty when they are disjoint).
inline Bounds Intersect(const Bounds& a, const Bounds& b)
{
  Bounds r;
  r.lo = glm::max(a.lo, b.lo);
  r.hi = glm::min(a.hi, b.hi);
  return r;
}
// SplitBounds of a type that splits only its box: box's two sides of the
// plane.
inline void SplitBox(const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  left = right = box;
  left.hi[axis] = std::min(box.hi[axis], pos);
  right.lo[axis] = std::max(box.lo[axis], pos);
}

// Name of type k (CR_PRIM_*).
const char* PrimTypeName(std::uint32_t k);

// Unified piece g against the box (insertion into cells; r: the scene's
// Ranges()); the caller has already checked that the box meets g's bounding
// box. Builders make the test conservative by passing a slightly enlarged
// box (grid_builder.cpp).
// A moving piece (Scene::MotionOfUnified) meets the box at some time of the
// shutter when its rest shape meets the box moved back by tau * motion for
// some tau in [0, 1]; the test takes the box around all those boxes, which
// holds them (conservative).
inline bool PrimOverlapsBox(const Scene& scene, const PrimRanges& r, std::uint32_t g, const glm::dvec3& lo,
                            const glm::dvec3& hi)
{
  glm::dvec3 l = lo, h = hi;
  if (scene.hasMotion) {
    const glm::dvec3 m(scene.MotionOfUnified(g));
    l = glm::min(lo, lo - m);
    h = glm::max(hi, hi - m);
  }
  return scene.Visit(r, g, [&](const auto& piece, std::uint32_t) { return OverlapsBox(piece, l, h); });
}

// SplitBounds of unified piece g (the BVH's spatial splits); a moving
// piece's sides are those of its swept box within `box` (SplitBox).
inline void PrimSplitBounds(const Scene& scene, const PrimRanges& r, std::uint32_t g, const Bounds& box, int axis,
                            float pos, Bounds& left, Bounds& right)
{
  if (scene.hasMotion && scene.MotionOfUnified(g) != glm::vec3(0.0f)) {
    SplitBox(Intersect(box, scene.UnifiedBounds(g)), axis, pos, left, right);
    return;
  }
  scene.Visit(r, g, [&](const auto& piece, std::uint32_t) { SplitBounds(piece, box, axis, pos, left, right); });
}

// v rounded to float towards -inf / +inf (the types' outward bounds).
inline float FloatDown(double v)
{
  float f = float(v);
  if (double(f) > v) f = std::nextafter(f, -INFINITY);
  return f;
}
inline float FloatUp(double v)
{
  float f = float(v);
  if (double(f) < v) f = std::nextafter(f, INFINITY);
  return f;
}

// Largest component magnitude (shared by the types' Scale and SurfaceAt).
inline double MaxAbs(const glm::dvec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

}  // namespace cr
