// SDF block (NFF extension `sdf` ... `sdf end`, docs/FORMATS.md): the host
// functions of host/prims/prim_host.h. Everything here evaluates the stored
// float program (kernels/types.h Sdf) with the kernels' own Sdf_Eval
// compiled with real = double, so the reference and the tracers read the
// same function. The fp64 reference marches with a threshold of 2^-40 of
// the block's size (no relaxation, a budget of 2^20 steps) and narrows the
// root to double precision by bisection between the last point outside the
// surface and the first one within the threshold.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {
namespace sdf_fp64 {
#define CR_FP64
#include "kernels/ray.h"
#include "kernels/sdf.h"
#undef CR_FP64
}  // namespace sdf_fp64

using ref::D3;

namespace {

glm::dvec3 Center(const Sdf& s) { return D3(s.center); }

double Eval(const Sdf& s, const glm::dvec3& x)
{
  const glm::dvec3 l = x - Center(s);
  const double p[3] = {l.x, l.y, l.z};
  return sdf_fp64::Sdf_Eval(&s, p);
}

double Size(const Sdf& s) { return std::max(MaxAbs(D3(s.hi) - D3(s.lo)), 1e-30); }

// Central differences at x, step h.
glm::dvec3 Gradient(const Sdf& s, const glm::dvec3& x, double h)
{
  glm::dvec3 g;
  for (int a = 0; a < 3; ++a) {
    glm::dvec3 e(0.0);
    e[a] = h;
    g[a] = Eval(s, x + e) - Eval(s, x - e);
  }
  const double len = glm::length(g);
  return len > 0.0 ? g / len : glm::dvec3(0.0, 1.0, 0.0);
}

// The ray's interval inside the bound, within [tmin, tmax].
bool BoundInterval(const Sdf& s, const ref::DRay& r, double& t0, double& t1)
{
  t0 = r.tmin;
  t1 = r.tmax;
  for (int a = 0; a < 3; ++a) {
    const double ta = (double(s.lo[a]) - r.o[a]) / r.d[a], tb = (double(s.hi[a]) - r.o[a]) / r.d[a];
    t0 = cr::fmax(t0, cr::fmin(ta, tb));
    t1 = cr::fmin(t1, cr::fmax(ta, tb));
  }
  return t0 <= t1;
}

// The reference march: the first root in the bound, or none.
bool RefMarch(const Sdf& s, const ref::DRay& r, double& tHit, std::vector<double>* closest = nullptr)
{
  double t0, t1;
  if (!BoundInterval(s, r, t0, t1)) return false;
  const double len = glm::length(r.d);
  if (!(len > 0.0)) return false;
  const double eps = std::ldexp(Size(s), -40), shell = double(s.eps);
  double t = t0;
  double f = Eval(s, r.o + t * r.d);
  // As the kernels: a ray starting in the bound leaves the eps shell first.
  if (t0 <= r.tmin) {
    for (std::uint32_t m = 0; std::fabs(f) < shell; ++m) {
      if (m == CR_SDF_SHELL_STEPS) return false;
      t += shell / len;
      if (t > t1) return false;
      f = Eval(s, r.o + t * r.d);
    }
  }
  const double side = f < 0.0 ? -1.0 : 1.0;
  double prevT = t, prevR = INFINITY;
  for (int n = 0; n < (1 << 20); ++n) {
    if (!(t <= t1)) return false;
    const double rr = side * Eval(s, r.o + t * r.d) / len;
    if (closest && rr > prevR) closest->push_back(prevT);  // a local minimum of the distance
    if (rr <= eps / len) {
      // Bisection between a point outside (side) and this one.
      double lo = prevT, hi = t;
      if (side * Eval(s, r.o + lo * r.d) > 0.0 && rr < 0.0)
        for (int k = 0; k < 80 && hi - lo > 0.0; ++k) {
          const double mid = 0.5 * (lo + hi);
          if (side * Eval(s, r.o + mid * r.d) > 0.0)
            lo = mid;
          else
            hi = mid;
        }
      tHit = rr < 0.0 ? hi : t;
      return tHit >= t0 && tHit <= t1;
    }
    prevT = t;
    prevR = rr;
    t += rr;
  }
  return false;
}

}  // namespace

const char* PrimTypeName(PrimTag<Sdf>) { return "sdf"; }

// A march stops within eps of the surface (robust mode then refines); the
// reference and the tracers differ by up to that where a ray starts in the
// eps shell or grazes the surface.
double HitSlack(const Sdf& s) { return 2.0 * double(s.eps); }

Bounds FloatBounds(const Sdf& s) { return StoredBounds(s); }

void SplitBounds(const Sdf& s, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(s), box), axis, pos, left, right);
}

// Conservative: every cell the bound meets (a distance program is a bound
// on the distance only where it is exact; a smooth union or a repetition
// need not be).
bool OverlapsBox(const Sdf& s, const glm::dvec3& lo, const glm::dvec3& hi) { return StoredBoundsMeet(s, lo, hi); }

double Scale(const Sdf& s) { return std::max(MaxAbs(D3(s.lo)), MaxAbs(D3(s.hi))); }

// Newton steps along the gradient onto the zero set; the normal is the
// gradient there.
LocalSurface SurfaceAt(const Scene&, const Sdf& s, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  const double h = std::max(std::ldexp(Size(s), -24), 1e-3 * double(s.eps));
  glm::dvec3 x = pApprox;
  for (int k = 0; k < 4; ++k) x -= Eval(s, x) * Gradient(s, x, h);
  ls.p = x;
  ls.ng = Gradient(s, x, h);
  ls.ns = ls.ng;
  return ls;
}

void RefBounds(const Sdf& s, glm::dvec3& lo, glm::dvec3& hi) { StoredRefBounds(s, lo, hi); }

int RefRoots(const ref::DRay& r, const Sdf& s, double t[2], double*, double*)
{
  double th;
  if (!RefMarch(s, r, th)) return 0;
  t[0] = th;
  return ref::KeepInRange(t, 1, r.tmin, r.tmax);
}

// The program's value: the distance where the program is exact (its leaves
// and min, max), a bound or an estimate elsewhere.
double RefDistance(const Sdf& s, const glm::dvec3& x) { return std::fabs(Eval(s, x)); }

glm::dvec3 RefNormal(const Sdf& s, const glm::dvec3& x)
{
  return Gradient(s, x, std::max(std::ldexp(Size(s), -24), 1e-3 * double(s.eps)));
}

void RefBall(const Sdf& s, glm::dvec3& mid, double& reach) { StoredRefBall(s, mid, reach); }

// The ray's closest approaches: the local minima of the distance along the
// reference march, and where the ray enters and leaves the bound. A surface
// that meets the bound's face (a cylinder's cap on the face) may lie just
// outside the bound in double and just inside it in float: the reference
// march leaves the bound before it and finds no root, while a tracer hits it
// within eps at the face (a downward ray out of the cylinder standing on
// scenes/geometry/sdf.nff's ground, the face at y = 0).
void RefNearTimes(const Sdf& s, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  ref::DRay w = r;
  w.tmin = t0;
  w.tmax = t1;
  std::vector<double> mins;
  double th, b0, b1;
  if (BoundInterval(s, w, b0, b1)) {
    mins.push_back(b0);
    mins.push_back(b1);
  }
  if (RefMarch(s, w, th, &mins)) mins.push_back(th);
  for (double t : mins)
    if (t >= t0 && t <= t1) ts.push_back(t);
}

// sdf xmin ymin zmin xmax ymax zmax eps steps relax, then operations in
// postfix order, one per line, then `sdf end`:
//   sphere cx cy cz r | box cx cy cz hx hy hz | roundbox cx cy cz hx hy hz r
//   torus cx cy cz R r | capsule ax ay az bx by bz r | cylinder cx cy cz r h
//   union | intersection | difference | smooth k
//   repeat px py pz nx ny nz ... end
// (docs/FORMATS.md). Coordinates are stored about the float centre of the
// bound.
bool ParseNff(PrimTag<Sdf>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "sdf") return false;
  const glm::dvec3 lo = st.Vec("the bound's minimum"), hi = st.Vec("the bound's maximum");
  for (int a = 0; a < 3; ++a)
    if (!(lo[a] < hi[a])) st.Fail(fmt::format("'sdf': the bound is empty on axis {} ({} >= {})", "xyz"[a], lo[a], hi[a]));
  const double eps = st.Number("the hit threshold eps");
  const long steps = st.Integer("the step budget");
  const double relax = st.Number("the relaxation factor");
  if (!(eps > 0.0)) st.Fail(fmt::format("'sdf': the hit threshold eps must be positive, got {}", eps));
  if (steps < 1 || steps > (1l << 20)) st.Fail(fmt::format("'sdf': the step budget must be 1 to 2^20, got {}", steps));
  if (!(relax >= 1.0 && relax < 2.0)) st.Fail(fmt::format("'sdf': the relaxation factor must be in [1, 2), got {}", relax));
  Sdf s{};
  const glm::dvec3 mid = 0.5 * (lo + hi);
  for (int a = 0; a < 3; ++a) {
    s.center[a] = float(mid[a]);
    s.lo[a] = FloatDown(lo[a]);
    s.hi[a] = FloatUp(hi[a]);
  }
  const glm::dvec3 c = D3(s.center);
  s.eps = float(eps);
  s.steps = std::uint32_t(steps);
  s.relax = float(relax);
  int depth = 0, repeats = 0;
  auto push = [&](std::uint32_t op, std::initializer_list<double> args, long at) {
    if (s.count >= CR_SDF_MAX_OPS)
      st.FailAt(at, fmt::format("'sdf': more than {} operations in one block", CR_SDF_MAX_OPS));
    SdfOp& o = s.op[s.count++];
    o.op = op;
    int i = 0;
    for (double v : args) o.a[i++] = float(v);
  };
  auto point = [&](const char* what) { return st.Vec(what) - c; };
  auto positive = [&](double v, const char* what, long at) {
    if (!(v > 0.0)) st.FailAt(at, fmt::format("'sdf': {} must be positive, got {}", what, v));
    return v;
  };
  for (;;) {
    const std::string w = st.Word("an operation or 'sdf end'");
    const long at = st.TokenLine();
    std::uint32_t op = 0;
    if (w == "sdf") {
      const std::string e = st.Word("'end'");
      if (e != "end") st.FailAt(st.TokenLine(), fmt::format("'sdf': expected 'sdf end', got 'sdf {}'", e));
      break;
    } else if (w == "sphere") {
      const glm::dvec3 p = point("a sphere's centre");
      push(CR_SDF_SPHERE, {p.x, p.y, p.z, positive(st.Number("a sphere's radius"), "a sphere's radius", at)}, at);
    } else if (w == "box" || w == "roundbox") {
      const glm::dvec3 p = point("a box's centre"), h = st.Vec("a box's half extents");
      const double r = w == "roundbox" ? st.Number("a rounded box's radius") : 0.0;
      for (int a = 0; a < 3; ++a) positive(h[a], "a box's half extent", at);
      if (!(r >= 0.0 && r <= std::min({h.x, h.y, h.z})))
        st.FailAt(at, fmt::format("'sdf': a rounded box's radius must be in [0, its smallest half extent], got {}", r));
      push(CR_SDF_BOX, {p.x, p.y, p.z, h.x, h.y, h.z, r}, at);
    } else if (w == "torus") {
      const glm::dvec3 p = point("a torus's centre");
      const double big = positive(st.Number("a torus's ring radius"), "a torus's ring radius", at);
      push(CR_SDF_TORUS, {p.x, p.y, p.z, big, positive(st.Number("a torus's tube radius"), "a torus's tube radius", at)},
           at);
    } else if (w == "capsule") {
      const glm::dvec3 a = point("a capsule's end"), b = point("a capsule's end");
      push(CR_SDF_CAPSULE,
           {a.x, a.y, a.z, b.x, b.y, b.z, positive(st.Number("a capsule's radius"), "a capsule's radius", at)}, at);
    } else if (w == "cylinder") {
      const glm::dvec3 p = point("a cylinder's centre");
      const double r = positive(st.Number("a cylinder's radius"), "a cylinder's radius", at);
      push(CR_SDF_CYLINDER, {p.x, p.y, p.z, r, positive(st.Number("a cylinder's half height"), "a cylinder's half height", at)},
           at);
    } else if (w == "union" || w == "intersection" || w == "difference" || w == "smooth") {
      if (depth < 2) st.FailAt(at, fmt::format("'sdf': '{}' needs two operands before it (postfix order)", w));
      op = w == "union" ? CR_SDF_UNION : w == "intersection" ? CR_SDF_INTERSECTION : w == "difference" ? CR_SDF_DIFFERENCE : CR_SDF_SMOOTH_UNION;
      const double k = op == CR_SDF_SMOOTH_UNION ? positive(st.Number("a smooth union's radius k"), "a smooth union's radius k", at) : 0.0;
      push(op, {k}, at);
      --depth;
      continue;
    } else if (w == "repeat") {
      const glm::dvec3 period = st.Vec("a repetition's period");
      const glm::dvec3 n = st.Vec("a repetition's copy count");
      for (int a = 0; a < 3; ++a) {
        if (!(period[a] >= 0.0)) st.FailAt(at, fmt::format("'sdf': a repetition's period must be >= 0 (0: none), got {}", period[a]));
        if (!(n[a] >= 0.0 && n[a] == std::floor(n[a]) && n[a] <= 1e6))
          st.FailAt(at, fmt::format("'sdf': a repetition's copy count must be a whole number 0 to 10^6, got {}", n[a]));
      }
      if (repeats + 1 > CR_SDF_MAX_STACK) st.FailAt(at, fmt::format("'sdf': repetitions nest deeper than {}", CR_SDF_MAX_STACK));
      ++repeats;
      push(CR_SDF_REPEAT, {period.x, period.y, period.z, n.x, n.y, n.z}, at);
      continue;
    } else if (w == "end") {
      if (repeats == 0) st.FailAt(at, "'sdf': 'end' without a 'repeat' to close (the block ends with 'sdf end')");
      --repeats;
      push(CR_SDF_END_REPEAT, {}, at);
      continue;
    } else {
      st.FailAt(at, fmt::format("'sdf': unknown operation '{}' (sphere, box, roundbox, torus, capsule, cylinder, union, "
                                "intersection, difference, smooth, repeat, end, or 'sdf end')",
                                w));
    }
    if (++depth > CR_SDF_MAX_STACK)
      st.FailAt(at, fmt::format("'sdf': more than {} operands pending (combine them sooner)", CR_SDF_MAX_STACK));
  }
  if (repeats != 0) st.Fail("'sdf': a 'repeat' is not closed by 'end' before 'sdf end'");
  if (depth != 1)
    st.Fail(depth == 0 ? std::string("'sdf': the block has no shape")
                       : fmt::format("'sdf': {} shapes left uncombined at 'sdf end' (add union, intersection, ...)", depth));
  PrimInfo info = st.Info(CR_PRIM_SDF);
  info.firstPiece = scene.AddPiece(s, scene.NumPrims());
  info.nPieces = 1;
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
