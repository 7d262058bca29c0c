// Axis-aligned box (NFF extension `box xmin ymin zmin xmax ymax zmax`,
// docs/FORMATS.md): the host functions of host/prims/prim_host.h. Its
// surface is the six faces; the float box is the primitive itself, so its
// bounds are exact.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {

using ref::D3;

namespace {

// The face nearest p (a point inside the box or on it): its axis and side
// (0: lo, 1: hi), the first such face in axis order on ties.
void NearestFace(const Box& b, const glm::dvec3& p, int& axis, int& side)
{
  double best = INFINITY;
  axis = 0;
  side = 0;
  for (int a = 0; a < 3; ++a) {
    const double dLo = std::fabs(p[a] - double(b.lo[a])), dHi = std::fabs(double(b.hi[a]) - p[a]);
    if (dLo < best) {
      best = dLo;
      axis = a;
      side = 0;
    }
    if (dHi < best) {
      best = dHi;
      axis = a;
      side = 1;
    }
  }
}

glm::dvec3 Clamp(const Box& b, const glm::dvec3& p) { return glm::clamp(p, D3(b.lo), D3(b.hi)); }

bool Inside(const Box& b, const glm::dvec3& p)
{
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= double(b.lo[a]) && p[a] <= double(b.hi[a]))) return false;
  return true;
}

}  // namespace

const char* PrimTypeName(PrimTag<Box>) { return "box"; }

Bounds FloatBounds(const Box& b) { return StoredBounds(b); }

// Its box's two sides (the box itself is not cut).
void SplitBounds(const Box& p, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(p), box), axis, pos, left, right);
}

// The surface meets the cell iff the closed cell meets the closed box and
// does not lie in the box's open interior. Exact.
bool OverlapsBox(const Box& b, const glm::dvec3& lo, const glm::dvec3& hi)
{
  bool interior = true;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > double(b.hi[a]) || hi[a] < double(b.lo[a])) return false;
    interior = interior && lo[a] > double(b.lo[a]) && hi[a] < double(b.hi[a]);
  }
  return !interior;
}

double Scale(const Box& b) { return std::max(MaxAbs(D3(b.lo)), MaxAbs(D3(b.hi))); }

// The nearest point of the nearest face; the normal is that face's.
LocalSurface SurfaceAt(const Scene&, const Box& b, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  ls.p = Clamp(b, pApprox);
  int axis, side;
  NearestFace(b, ls.p, axis, side);
  ls.p[axis] = side ? double(b.hi[axis]) : double(b.lo[axis]);
  ls.ng = glm::dvec3(0.0);
  ls.ng[axis] = side ? 1.0 : -1.0;
  ls.ns = ls.ng;
  return ls;
}

void RefBounds(const Box& b, glm::dvec3& lo, glm::dvec3& hi) { StoredRefBounds(b, lo, hi); }

// The slab test of kernels/box.h in double: entry and exit, both roots.
int RefRoots(const ref::DRay& r, const Box& b, double t[2], double*, double*)
{
  double tn = -INFINITY, tf = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const double t0 = (double(b.lo[a]) - r.o[a]) / r.d[a], t1 = (double(b.hi[a]) - r.o[a]) / r.d[a];
    tn = cr::fmax(tn, cr::fmin(t0, t1));
    tf = cr::fmin(tf, cr::fmax(t0, t1));
  }
  if (!(tn <= tf)) return 0;
  t[0] = tn;
  t[1] = tf;
  return ref::KeepInRange(t, tn == tf ? 1 : 2, r.tmin, r.tmax);
}

double RefDistance(const Box& b, const glm::dvec3& x)
{
  if (!Inside(b, x)) return glm::length(x - Clamp(b, x));
  int axis, side;
  NearestFace(b, x, axis, side);
  return side ? double(b.hi[axis]) - x[axis] : x[axis] - double(b.lo[axis]);
}

glm::dvec3 RefNormal(const Box& b, const glm::dvec3& x)
{
  int axis, side;
  NearestFace(b, Clamp(b, x), axis, side);
  glm::dvec3 n(0.0);
  n[axis] = side ? 1.0 : -1.0;
  return n;
}

void RefBall(const Box& b, glm::dvec3& mid, double& reach) { StoredRefBall(b, mid, reach); }

// The closest approaches to the twelve edges.
void RefNearTimes(const Box& b, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const glm::dvec3 lo = D3(b.lo), hi = D3(b.hi);
  const glm::dvec3 a = r.o + t0 * r.d, c = r.o + t1 * r.d;
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k < 4; ++k) {
      glm::dvec3 p = lo;
      p[(axis + 1) % 3] = (k & 1) ? hi[(axis + 1) % 3] : lo[(axis + 1) % 3];
      p[(axis + 2) % 3] = (k & 2) ? hi[(axis + 2) % 3] : lo[(axis + 2) % 3];
      glm::dvec3 q = p;
      q[axis] = hi[axis];
      ts.push_back(t0 + (t1 - t0) * ref::ClosestOnSegment(a, c, p, q));
    }
}

// box xmin ymin zmin xmax ymax zmax (an extension of NFF): each min at most
// its max; a flat box (min = max on an axis) is a rectangle.
bool ParseNff(PrimTag<Box>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "box") return false;
  const glm::dvec3 lo = st.Vec("a min coordinate");
  const glm::dvec3 hi = st.Vec("a max coordinate");
  const char* axes = "xyz";
  Box b{};
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = float(lo[a]);
    b.hi[a] = float(hi[a]);
    if (!(b.lo[a] <= b.hi[a]))
      st.Fail(fmt::format("'box': {}min {} is greater than {}max {}", axes[a], lo[a], axes[a], hi[a]));
  }
  PrimInfo info = st.Info(CR_PRIM_BOX);
  info.firstPiece = scene.AddPiece(b, scene.NumPrims());
  info.nPieces = 1;
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
