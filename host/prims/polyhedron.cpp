// Convex polyhedron (NFF extension `polyhedron N` followed by N planes
// `a b c d`, docs/FORMATS.md): the host functions of host/prims/prim_host.h.
// The stored form (kernels/types.h Polyhedron) is each plane normalised in
// double, its normal rounded to float, and re-expressed about the float
// centre of the solid's vertices; everything here, the fp64 reference
// included, works from that stored float data, as the kernels do.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {

using ref::D3;

namespace {

using LD = long double;

struct Plane {
  glm::dvec3 n;
  double w;  // n . x + w <= 0 inside
};

glm::dvec3 Center(const Polyhedron& p) { return D3(p.center); }
glm::dvec3 Normal(const Polyhedron& p, std::uint32_t k) { return D3(p.plane[k]); }

// Plane k's value at x (coordinates about the centre): its signed distance
// times |n| (about 1).
double Value(const Polyhedron& p, std::uint32_t k, const glm::dvec3& x)
{
  return glm::dot(Normal(p, k), x) + double(p.plane[k][3]);
}

// The plane whose value at x (about the centre) is largest: the face x
// lies on, or nearest from inside, or the most violated from outside.
std::uint32_t OuterPlane(const Polyhedron& p, const glm::dvec3& x, double* value = nullptr)
{
  std::uint32_t best = 0;
  double v = -INFINITY;
  for (std::uint32_t k = 0; k < p.count; ++k) {
    const double vk = Value(p, k, x) / glm::length(Normal(p, k));
    if (vk > v) {
      v = vk;
      best = k;
    }
  }
  if (value) *value = v;
  return best;
}

// The vertices of {x : n_k . x + w_k <= 0}: every point where three planes
// meet that satisfies the others (tolerance relative to the coordinates).
std::vector<glm::dvec3> Vertices(const std::vector<Plane>& planes)
{
  std::vector<glm::dvec3> out;
  const std::size_t n = planes.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k) {
        const glm::dvec3 &a = planes[i].n, &b = planes[j].n, &c = planes[k].n;
        const glm::dvec3 bc = glm::cross(b, c);
        const double det = glm::dot(a, bc);
        if (std::fabs(det) < 1e-12) continue;
        const glm::dvec3 x =
            (-planes[i].w * bc - planes[j].w * glm::cross(c, a) - planes[k].w * glm::cross(a, b)) / det;
        const double tol = 1e-9 * (1.0 + MaxAbs(x));
        bool inside = true;
        for (std::size_t m = 0; m < n && inside; ++m) inside = glm::dot(planes[m].n, x) + planes[m].w <= tol;
        if (inside) out.push_back(x);
      }
  return out;
}

std::vector<Plane> StoredPlanes(const Polyhedron& p)
{
  std::vector<Plane> out;
  for (std::uint32_t k = 0; k < p.count; ++k) out.push_back({Normal(p, k), double(p.plane[k][3])});
  return out;
}

}  // namespace

const char* PrimTypeName(PrimTag<Polyhedron>) { return "polyhedron"; }

Bounds FloatBounds(const Polyhedron& p) { return StoredBounds(p); }

void SplitBounds(const Polyhedron& p, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(p), box), axis, pos, left, right);
}

// The surface meets the cell unless the cell lies outside one of the planes
// or (its eight corners inside every plane) in the solid's interior.
// Conservative: a cell outside the solid but outside none of its planes
// (beyond an edge) counts as met.
bool OverlapsBox(const Polyhedron& p, const glm::dvec3& lo, const glm::dvec3& hi)
{
  if (!StoredBoundsMeet(p, lo, hi)) return false;
  const glm::dvec3 c = Center(p);
  bool interior = true;
  for (std::uint32_t k = 0; k < p.count; ++k) {
    const glm::dvec3 n = Normal(p, k);
    double vmin = double(p.plane[k][3]), vmax = vmin;
    for (int a = 0; a < 3; ++a) {
      const double v0 = n[a] * (lo[a] - c[a]), v1 = n[a] * (hi[a] - c[a]);
      vmin += std::min(v0, v1);
      vmax += std::max(v0, v1);
    }
    const double pad = 1e-12 * (std::fabs(vmin) + std::fabs(vmax) + MaxAbs(hi - c) + MaxAbs(lo - c));
    if (vmin > pad) return false;  // the whole cell outside plane k
    interior = interior && vmax < -pad;
  }
  return !interior;
}

double Scale(const Polyhedron& p) { return std::max(MaxAbs(D3(p.lo)), MaxAbs(D3(p.hi))); }

// The nearest point of the face the point lies on (the plane of largest
// value); the normal is that face's.
LocalSurface SurfaceAt(const Scene&, const Polyhedron& p, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  const glm::dvec3 x = pApprox - Center(p);
  const std::uint32_t k = OuterPlane(p, x);
  const glm::dvec3 n = glm::normalize(Normal(p, k));
  ls.p = Center(p) + x - (Value(p, k, x) / glm::length(Normal(p, k))) * n;
  ls.ng = n;
  ls.ns = n;
  return ls;
}

void RefBounds(const Polyhedron& p, glm::dvec3& lo, glm::dvec3& hi) { StoredRefBounds(p, lo, hi); }

// The slab clipping of kernels/polyhedron.h in long double (o - c and the
// products of two floats exact there): entry and exit, both roots.
int RefRoots(const ref::DRay& r, const Polyhedron& p, double t[2], double*, double*)
{
  LD x[3], d[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = LD(r.o[i]) - LD(p.center[i]);
    d[i] = LD(r.d[i]);
  }
  LD tn = -INFINITY, tf = INFINITY;
  for (std::uint32_t k = 0; k < p.count; ++k) {
    const float* n = p.plane[k];
    const LD s = (LD(n[0]) * x[0] + LD(n[1]) * x[1] + LD(n[2]) * x[2]) + LD(n[3]);
    const LD e = LD(n[0]) * d[0] + LD(n[1]) * d[1] + LD(n[2]) * d[2];
    if (e == 0) {
      if (!(s < 0)) return 0;
      continue;
    }
    const LD tk = -s / e;
    if (e < 0)
      tn = std::max(tn, tk);
    else
      tf = std::min(tf, tk);
  }
  if (!(tn <= tf)) return 0;
  t[0] = double(tn);
  t[1] = double(tf);
  return ref::KeepInRange(t, t[0] == t[1] ? 1 : 2, r.tmin, r.tmax);
}

// Inside: the distance to the nearest face's plane (exact for a convex
// solid). Outside: the largest plane distance, a lower bound that is exact
// where the nearest point lies inside a face.
double RefDistance(const Polyhedron& p, const glm::dvec3& x)
{
  double v;
  OuterPlane(p, x - Center(p), &v);
  return std::fabs(v);
}

glm::dvec3 RefNormal(const Polyhedron& p, const glm::dvec3& x)
{
  return glm::normalize(Normal(p, OuterPlane(p, x - Center(p))));
}

void RefBall(const Polyhedron& p, glm::dvec3& mid, double& reach) { StoredRefBall(p, mid, reach); }

// Where the ray crosses each face's plane: its closest approaches to the
// edges and vertices lie among them.
void RefNearTimes(const Polyhedron& p, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const glm::dvec3 x = r.o - Center(p);
  for (std::uint32_t k = 0; k < p.count; ++k) {
    const double e = glm::dot(Normal(p, k), r.d);
    if (e == 0.0) continue;
    const double t = -Value(p, k, x) / e;
    if (t >= t0 && t <= t1) ts.push_back(t);
  }
}

// polyhedron N, then N planes a b c d: the convex solid where every
// a x + b y + c z + d <= 0. At least 4 and at most CR_POLY_MAX_PLANES
// planes; the solid must be bounded and have volume. Each plane is
// normalised in double, stored about the float centre of the solid's
// vertices with its normal rounded to float, and the bounds are those of
// the stored planes' vertices, rounded outward.
bool ParseNff(PrimTag<Polyhedron>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "polyhedron") return false;
  const long n = st.Integer("the plane count");
  if (n < 4 || n > long(CR_POLY_MAX_PLANES))
    st.Fail(fmt::format("'polyhedron': {} planes (a bounded solid needs 4 to {})", n, CR_POLY_MAX_PLANES));
  std::vector<Plane> planes;
  for (long k = 0; k < n; ++k) {
    const glm::dvec3 abc = st.Vec("a plane coefficient");
    const double d = st.Number("a plane coefficient");
    const double len = glm::length(abc);
    if (!(len > 0.0) || !std::isfinite(len) || !std::isfinite(d))
      st.Fail(fmt::format("'polyhedron': plane {} ({} {} {} {}) has no direction", k + 1, abc.x, abc.y, abc.z, d));
    planes.push_back({abc / len, d / len});
  }
  // Bounded: no vertex on a far box around it (a direction no plane
  // closes off would reach that box).
  double far = 1.0;
  for (const Plane& pl : planes) far = std::max(far, std::fabs(pl.w));
  far *= 1048576.0;
  std::vector<Plane> closed = planes;
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) {
      glm::dvec3 nn(0.0);
      nn[a] = s;
      closed.push_back({nn, -far});
    }
  for (const glm::dvec3& v : Vertices(closed))
    if (MaxAbs(v) > 0.5 * far) st.Fail("'polyhedron': the planes do not bound a solid (it is unbounded)");
  const std::vector<glm::dvec3> verts = Vertices(planes);
  if (verts.size() < 4) st.Fail("'polyhedron': the planes enclose no solid (empty or flat)");
  glm::dvec3 mid(0.0);
  for (const glm::dvec3& v : verts) mid += v;
  mid /= double(verts.size());
  Polyhedron p{};
  p.count = std::uint32_t(n);
  for (int a = 0; a < 3; ++a) p.center[a] = float(mid[a]);
  const glm::dvec3 c = D3(p.center);
  double size = 0.0;
  for (const glm::dvec3& v : verts) size = std::max(size, MaxAbs(v - c));
  for (long k = 0; k < n; ++k) {
    for (int a = 0; a < 3; ++a) p.plane[k][a] = float(planes[k].n[a]);
    // w about the stored centre, with the stored (rounded) normal.
    p.plane[k][3] = float(planes[k].w + glm::dot(planes[k].n, c));
    const double inner = glm::dot(D3(p.plane[k]), mid - c) + double(p.plane[k][3]);
    if (!(inner < -1e-9 * size)) st.Fail("'polyhedron': the planes enclose no solid (empty or flat)");
  }
  // Bounds: the stored planes' vertices, padded by a few ulps of the size.
  const std::vector<glm::dvec3> sv = Vertices(StoredPlanes(p));
  if (sv.size() < 4) st.Fail("'polyhedron': the planes enclose no solid once rounded to float");
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::dvec3& v : sv) {
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
  const double pad = 1e-6 * size;
  for (int a = 0; a < 3; ++a) {
    p.lo[a] = FloatDown(c[a] + lo[a] - pad);
    p.hi[a] = FloatUp(c[a] + hi[a] + pad);
  }
  PrimInfo info = st.Info(CR_PRIM_POLYHEDRON);
  info.firstPiece = scene.AddPiece(p, scene.NumPrims());
  info.nPieces = 1;
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
