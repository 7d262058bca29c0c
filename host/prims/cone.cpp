// Open truncated cone or cylinder (NFF `c`): the host functions of
// host/prims/prim_host.h.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {

using ref::D3;

namespace {

// The box of the two end discs: a disc of radius r normal to unit axis w
// extends r * sqrt(1 - w_i^2) along axis i.
void DiscBox(const Cone& c, glm::dvec3& lo, glm::dvec3& hi)
{
  const glm::dvec3 p0 = D3(c.base), p1 = D3(c.apex);
  const glm::dvec3 w = glm::normalize(p1 - p0);
  const glm::dvec3 e = glm::sqrt(glm::max(glm::dvec3(1.0) - w * w, glm::dvec3(0.0)));
  lo = glm::min(p0 - e * double(c.baseRadius), p1 - e * double(c.apexRadius));
  hi = glm::max(p0 + e * double(c.baseRadius), p1 + e * double(c.apexRadius));
}

// Point p against the cone's axis, in double: the unit axis w, the height
// H, p's axial position s from the base and its offset from the axis.
struct AxisPoint {
  glm::dvec3 w;
  double H, s;
  glm::dvec3 radial;
};
AxisPoint AxisPointOf(const Cone& cn, const glm::dvec3& p)
{
  AxisPoint a;
  const glm::dvec3 b = D3(cn.base);
  a.w = D3(cn.apex) - b;
  a.H = glm::length(a.w);
  a.w /= a.H;
  const glm::dvec3 q = p - b;
  a.s = glm::dot(q, a.w);
  a.radial = q - a.s * a.w;
  return a;
}

}  // namespace

const char* PrimTypeName(PrimTag<Cone>) { return "cone"; }

// The box of the end discs, padded by a relative epsilon and rounded outward
// to float.
Bounds FloatBounds(const Cone& c)
{
  glm::dvec3 lo, hi;
  DiscBox(c, lo, hi);
  const glm::dvec3 pad = (hi - lo) * 1e-6 + glm::abs(lo) * 1e-7 + glm::abs(hi) * 1e-7;
  lo -= pad;
  hi += pad;
  Bounds b;
  b.lo = glm::vec3(lo);
  b.hi = glm::vec3(hi);
  for (int a = 0; a < 3; ++a) {
    if (double(b.lo[a]) > lo[a]) b.lo[a] = std::nextafter(b.lo[a], -INFINITY);
    if (double(b.hi[a]) < hi[a]) b.hi[a] = std::nextafter(b.hi[a], INFINITY);
  }
  return b;
}

// Its box's two sides (the cone itself is not cut).
void SplitBounds(const Cone& p, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(p), box), axis, pos, left, right);
}

// A conservative test, tighter than the bounding box. The box (through its
// bounding sphere) must meet the slab 0 <= s <= H along the axis, and its
// centre's distance to the axis segment must lie in [rmin - R, rmax + R], R
// the box's half diagonal (distance to a segment is 1-Lipschitz and every
// surface point lies at distance r(s) from it).
bool OverlapsBox(const Cone& cn, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const glm::dvec3 p0 = D3(cn.base), p1 = D3(cn.apex);
  glm::dvec3 w = p1 - p0;
  const double H = glm::length(w);
  if (!(H > 0.0)) return true;  // never hit (Cone_Test); keep the box answer
  w /= H;
  const glm::dvec3 c = 0.5 * (lo + hi);
  const glm::dvec3 h = 0.5 * (hi - lo);
  // Axial slab: the box projects onto the axis as sc +- sr.
  const double sc = glm::dot(c - p0, w);
  const double sr = h.x * std::fabs(w.x) + h.y * std::fabs(w.y) + h.z * std::fabs(w.z);
  if (sc + sr < 0.0 || sc - sr > H) return false;
  // Radial shell around the axis segment.
  const double R = glm::length(h);
  const double d = glm::length(c - (p0 + std::clamp(sc, 0.0, H) * w));
  const double r0 = double(cn.baseRadius), r1 = double(cn.apexRadius);
  const double rMin = std::min(r0, r1), rMax = std::max(r0, r1);
  return d <= rMax + R && d >= rMin - R;
}

double Scale(const Cone& c) { return std::max(MaxAbs(D3(c.base)) + c.baseRadius, MaxAbs(D3(c.apex)) + c.apexRadius); }

// Projection onto the surface line of the half-plane through the axis.
LocalSurface SurfaceAt(const Scene&, const Cone& cn, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  const glm::dvec3 base = D3(cn.base), apex = D3(cn.apex);
  glm::dvec3 w = apex - base;
  const double H = glm::length(w);
  w /= H;
  const double k = (double(cn.apexRadius) - double(cn.baseRadius)) / H;
  const glm::dvec3 q = pApprox - base;
  const double s = std::clamp(glm::dot(q, w), 0.0, H);
  const glm::dvec3 radial = q - glm::dot(q, w) * w;
  const double rl = glm::length(radial);
  const glm::dvec3 rdir =
      rl > 0.0 ? radial / rl
               : glm::normalize(glm::cross(w, std::fabs(w.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
  ls.p = base + s * w + (double(cn.baseRadius) + k * s) * rdir;
  ls.ng = glm::normalize(rdir - k * w);
  ls.ns = ls.ng;
  return ls;
}

void RefBounds(const Cone& c, glm::dvec3& lo, glm::dvec3& hi)
{
  glm::dvec3 l, h;
  DiscBox(c, l, h);
  const glm::dvec3 pad = (h - l) * 1e-9 + (glm::abs(l) + glm::abs(h)) * 1e-12;
  lo = l - pad;
  hi = h + pad;
}

int RefRoots(const ref::DRay& r, const Cone& cn, double t[2], double*, double*)
{
  const glm::dvec3 b = D3(cn.base);
  glm::dvec3 w = D3(cn.apex) - b;
  const double H = glm::length(w);
  if (!(H > 0.0)) return 0;
  w /= H;
  const double r0 = cn.baseRadius, k = (double(cn.apexRadius) - r0) / H;
  const glm::dvec3 dl = r.o - b;
  const double ds = glm::dot(r.d, w), os = glm::dot(dl, w);
  const glm::dvec3 dR = r.d - ds * w, oR = dl - os * w;
  const double rb = r0 + k * os;
  const double A = glm::dot(dR, dR) - k * k * ds * ds;
  const double Bh = glm::dot(oR, dR) - k * ds * rb;
  const double C = glm::dot(oR, oR) - rb * rb;
  double roots[2];
  int n = 0;
  if (A == 0.0) {
    if (Bh == 0.0) return 0;
    roots[0] = -C / (2.0 * Bh);
    n = 1;
  } else {
    // Bh^2 - A C without cancellation (see kernels/cone.h).
    const glm::dvec3 e = rb * dR - k * ds * oR, x = glm::cross(oR, dR);
    n = ref::Quadratic(A, Bh, C, glm::dot(e, e) - glm::dot(x, x), roots);
  }
  int k2 = 0;
  for (int i = 0; i < n; ++i) {
    const double s = os + roots[i] * ds;
    if (roots[i] >= r.tmin && roots[i] <= r.tmax && s >= 0.0 && s <= H) t[k2++] = roots[i];
  }
  return k2;
}

// In the half-plane (s, rho) through the axis the surface is the segment
// (0, r0)-(H, r1).
double RefDistance(const Cone& cn, const glm::dvec3& p)
{
  const AxisPoint a = AxisPointOf(cn, p);
  const double rho = glm::length(a.radial);
  const glm::dvec2 P(a.s, rho), S0(0.0, cn.baseRadius), S1(a.H, cn.apexRadius);
  const glm::dvec2 e = S1 - S0;
  const double u = std::clamp(glm::dot(P - S0, e) / glm::dot(e, e), 0.0, 1.0);
  return glm::length(P - (S0 + u * e));
}

glm::dvec3 RefNormal(const Cone& cn, const glm::dvec3& p)
{
  const AxisPoint a = AxisPointOf(cn, p);
  const double rl = glm::length(a.radial);
  if (rl == 0.0) return a.w;
  // The surface line rises by (r1 - r0) over H: the normal tilts back along -w.
  const double k = (double(cn.apexRadius) - double(cn.baseRadius)) / a.H;
  return glm::normalize(a.radial / rl - k * a.w);
}

void RefBall(const Cone& c, glm::dvec3& mid, double& reach)
{
  const glm::dvec3 pts[2] = {D3(c.base), D3(c.apex)};
  ref::BallOf(pts, 2, std::max(c.baseRadius, c.apexRadius), mid, reach);
}

// The closest approach to the axis, and the points abreast of both ends.
void RefNearTimes(const Cone& c, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const glm::dvec3 pts[2] = {D3(c.base), D3(c.apex)};
  const glm::dvec3 a = r.o + t0 * r.d, b = r.o + t1 * r.d;
  const double dl = glm::length(r.d);
  ts.push_back(t0 + (t1 - t0) * ref::ClosestOnSegment(a, b, pts[0], pts[1]));
  for (int k = 0; k < 2; ++k) ts.push_back(std::clamp(glm::dot(pts[k] - r.o, r.d) / (dl * dl), t0, t1));
}

// c  bx by bz rb  ax ay az ra (over one or two lines): negative radii make
// the inside visible.
bool ParseNff(PrimTag<Cone>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "c") return false;
  const glm::dvec3 b = st.Vec("a base coordinate");
  const double rb = st.Number("the base radius");
  const glm::dvec3 a = st.Vec("an apex coordinate");
  const double ra = st.Number("the apex radius");
  PrimInfo info = st.Info(CR_PRIM_CONE);
  info.insideVisible = rb < 0.0 || ra < 0.0;
  if ((rb < 0.0) != (ra < 0.0) && rb != 0.0 && ra != 0.0)
    Warn(fmt::format("{}:{}: cone radii of opposite signs: treated as inside-visible", st.file, st.line));
  const auto id = scene.NumPrims();
  const Cone cn{{float(b.x), float(b.y), float(b.z)}, float(std::fabs(rb)), {float(a.x), float(a.y), float(a.z)},
                float(std::fabs(ra))};
  const bool sameEnds = cn.base[0] == cn.apex[0] && cn.base[1] == cn.apex[1] && cn.base[2] == cn.apex[2];
  if (sameEnds || (cn.baseRadius == 0.0f && cn.apexRadius == 0.0f)) {
    Warn(fmt::format("{}:{}: degenerate cone ({}): skipped, id {} kept", st.file, st.line,
                     sameEnds ? "base and apex coincide" : "both radii are 0", id));
  } else {
    info.firstPiece = scene.AddPiece(cn, id);
    info.nPieces = 1;
  }
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
