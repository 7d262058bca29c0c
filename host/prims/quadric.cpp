// Quadric surface clipped to a box (NFF extension `quadric A B C D E F G H I
// J xmin ymin zmin xmax ymax zmax`, docs/FORMATS.md): the host functions of
// host/prims/prim_host.h. The stored form (kernels/types.h Quadric) is the
// statement's surface re-expressed about the clip box's float centre and
// scaled by a power of two; everything here, the fp64 reference included,
// works from that stored float data, as the kernels do.
#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {

using ref::D3;

namespace {

using LD = long double;

// Q's entries (xx yy zz xy xz yz) as a symmetric matrix, indices into q.
constexpr int kRow[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};

glm::dvec3 Center(const Quadric& s) { return D3(s.center); }
glm::dvec3 Half(const Quadric& s) { return D3(s.extent); }

// f and its gradient at x (coordinates about the centre), in double.
double F(const Quadric& s, const glm::dvec3& x, glm::dvec3* grad = nullptr)
{
  glm::dvec3 u(0.0);
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) u[i] += double(s.q[kRow[i][k]]) * x[k];
    u[i] += double(s.l[i]);
  }
  if (grad) *grad = 2.0 * u;
  double f = double(s.j);
  for (int i = 0; i < 3; ++i) f += x[i] * (u[i] + double(s.l[i]));
  return f;
}

// x moved onto the surface by Newton steps along the gradient (a point near
// the surface converges in a few steps; the closest point for a point near
// it, to second order).
glm::dvec3 Project(const Quadric& s, glm::dvec3 x)
{
  for (int it = 0; it < 16; ++it) {
    glm::dvec3 g;
    const double f = F(s, x, &g);
    const double gg = glm::dot(g, g);
    if (!(gg > 0.0)) break;
    const glm::dvec3 step = (f / gg) * g;
    x -= step;
    if (glm::length(step) <= 1e-15 * (glm::length(x) + 1e-300)) break;
  }
  return x;
}

glm::dvec3 UnitGradient(const Quadric& s, const glm::dvec3& x)
{
  glm::dvec3 g;
  F(s, x, &g);
  const double n = glm::length(g);
  return n > 0.0 ? g / n : glm::dvec3(0.0, 0.0, 1.0);
}

// Distance from x (about the centre) to the clip box.
double BoxDistance(const Quadric& s, const glm::dvec3& x)
{
  const glm::dvec3 h = Half(s);
  return glm::length(x - glm::clamp(x, -h, h));
}

// Interval [lo, hi] products and squares.
struct Iv {
  double lo, hi;
};
Iv Mul(Iv a, Iv b)
{
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  return {*std::min_element(p, p + 4), *std::max_element(p, p + 4)};
}
Iv Sq(Iv a)
{
  if (a.lo >= 0.0) return {a.lo * a.lo, a.hi * a.hi};
  if (a.hi <= 0.0) return {a.hi * a.hi, a.lo * a.lo};
  return {0.0, std::max(a.lo * a.lo, a.hi * a.hi)};
}
Iv Add(Iv a, Iv b) { return {a.lo + b.lo, a.hi + b.hi}; }
Iv Scaled(Iv a, double k) { return k >= 0.0 ? Iv{a.lo * k, a.hi * k} : Iv{a.hi * k, a.lo * k}; }

// Can f vanish on the box [lo, hi] (about the centre)? Interval arithmetic,
// conservative, refined by bisecting the box's longest side up to `depth`
// times where the interval holds 0.
bool MayVanish(const Quadric& s, glm::dvec3 lo, glm::dvec3 hi, int depth)
{
  Iv x[3];
  for (int i = 0; i < 3; ++i) x[i] = {lo[i], hi[i]};
  Iv f{double(s.j), double(s.j)};
  double mag = std::fabs(double(s.j));
  for (int i = 0; i < 3; ++i) {
    const Iv t = Scaled(Sq(x[i]), double(s.q[i]));
    const Iv l = Scaled(x[i], 2.0 * double(s.l[i]));
    f = Add(Add(f, t), l);
    mag += std::max(std::fabs(t.lo), std::fabs(t.hi)) + std::max(std::fabs(l.lo), std::fabs(l.hi));
  }
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int k = 0; k < 3; ++k) {
    const Iv t = Scaled(Mul(x[pairs[k][0]], x[pairs[k][1]]), 2.0 * double(s.q[3 + k]));
    f = Add(f, t);
    mag += std::max(std::fabs(t.lo), std::fabs(t.hi));
  }
  const double pad = 1e-12 * mag;  // double's rounding of the sums, generously
  if (f.lo > pad || f.hi < -pad) return false;
  if (depth == 0) return true;
  int a = 0;
  for (int i = 1; i < 3; ++i)
    if (hi[i] - lo[i] > hi[a] - lo[a]) a = i;
  const double mid = 0.5 * (lo[a] + hi[a]);
  glm::dvec3 h1 = hi, l2 = lo;
  h1[a] = mid;
  l2[a] = mid;
  return MayVanish(s, lo, h1, depth - 1) || MayVanish(s, l2, hi, depth - 1);
}

}  // namespace

const char* PrimTypeName(PrimTag<Quadric>) { return "quadric"; }

Bounds FloatBounds(const Quadric& s)
{
  Bounds b;
  for (int i = 0; i < 3; ++i) {
    b.lo[i] = FloatDown(double(s.center[i]) - double(s.extent[i]));
    b.hi[i] = FloatUp(double(s.center[i]) + double(s.extent[i]));
  }
  return b;
}

void SplitBounds(const Quadric& s, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(s), box), axis, pos, left, right);
}

// The cell's part inside the clip box, where f may vanish (interval
// arithmetic over up to 64 sub-boxes): conservative.
bool OverlapsBox(const Quadric& s, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const glm::dvec3 c = Center(s), h = Half(s);
  const glm::dvec3 a = glm::max(lo - c, -h), b = glm::min(hi - c, h);
  for (int i = 0; i < 3; ++i)
    if (!(a[i] <= b[i])) return false;
  return MayVanish(s, a, b, 6);
}

double Scale(const Quadric& s) { return MaxAbs(Center(s)) + MaxAbs(Half(s)); }

LocalSurface SurfaceAt(const Scene&, const Quadric& s, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  const glm::dvec3 x = Project(s, pApprox - Center(s));
  ls.p = Center(s) + x;
  ls.ng = UnitGradient(s, x);
  ls.ns = ls.ng;
  return ls;
}

void RefBounds(const Quadric& s, glm::dvec3& lo, glm::dvec3& hi)
{
  const Bounds b = FloatBounds(s);
  lo = glm::dvec3(b.lo);
  hi = glm::dvec3(b.hi);
}

// The quadratic along the ray in long double (x0 = o - centre is exact
// there), its stable roots, each kept when in [tmin, tmax] and in the box.
int RefRoots(const ref::DRay& r, const Quadric& s, double t[2], double*, double*)
{
  LD x[3], d[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = LD(r.o[i]) - LD(s.center[i]);
    d[i] = LD(r.d[i]);
  }
  LD a = 0, bh = 0, c = LD(s.j);
  for (int i = 0; i < 3; ++i) {
    LD qd = 0, u = LD(s.l[i]);
    for (int k = 0; k < 3; ++k) {
      qd += LD(s.q[kRow[i][k]]) * d[k];
      u += LD(s.q[kRow[i][k]]) * x[k];
    }
    a += qd * d[i];
    bh += u * d[i];
    c += x[i] * (u + LD(s.l[i]));
  }
  const LD disc = bh * bh - a * c;
  if (disc < 0 || (a == 0 && bh == 0)) return 0;
  const LD q = -(bh + std::copysign(std::sqrt(disc), bh));
  const LD r0 = q / a, r1 = q != 0 ? c / q : r0;
  const LD roots[2] = {std::min(r0, r1), std::max(r0, r1)};
  int n = 0;
  for (LD tr : roots) {
    if (!(tr >= LD(r.tmin) && tr <= LD(r.tmax))) continue;
    bool in = true;
    for (int i = 0; i < 3; ++i) in = in && std::fabs(x[i] + tr * d[i]) <= LD(s.extent[i]);
    if (in && (n == 0 || double(tr) != t[0])) t[n++] = double(tr);
  }
  return n;
}

double RefDistance(const Quadric& s, const glm::dvec3& p)
{
  const glm::dvec3 x = p - Center(s);
  const glm::dvec3 y = Project(s, x);
  double d = glm::length(x - y);
  if (!std::isfinite(d)) d = INFINITY;
  return BoxDistance(s, y) > 0.0 ? std::max(d, BoxDistance(s, x)) : d;
}

glm::dvec3 RefNormal(const Quadric& s, const glm::dvec3& p) { return UnitGradient(s, p - Center(s)); }

void RefBall(const Quadric& s, glm::dvec3& mid, double& reach)
{
  const glm::dvec3 pts[2] = {Center(s) - Half(s), Center(s) + Half(s)};
  ref::BallOf(pts, 2, 0.0, mid, reach);
}

// Where f along the ray has its extremum (a tangent's closest approach) and
// where the ray crosses the clip box's planes (the rim).
void RefNearTimes(const Quadric& s, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const glm::dvec3 x = r.o - Center(s), h = Half(s);
  glm::dvec3 qd, u;
  for (int i = 0; i < 3; ++i) {
    qd[i] = u[i] = 0.0;
    for (int k = 0; k < 3; ++k) {
      qd[i] += double(s.q[kRow[i][k]]) * r.d[k];
      u[i] += double(s.q[kRow[i][k]]) * x[k];
    }
    u[i] += double(s.l[i]);
  }
  const double a = glm::dot(r.d, qd), bh = glm::dot(r.d, u);
  if (a != 0.0) ts.push_back(std::clamp(-bh / a, t0, t1));
  for (int i = 0; i < 3; ++i) {
    if (r.d[i] == 0.0) continue;
    for (double side : {-h[i], h[i]}) {
      const double t = (side - x[i]) / r.d[i];
      if (t >= t0 && t <= t1) ts.push_back(t);
    }
  }
}

// quadric A B C D E F G H I J xmin ymin zmin xmax ymax zmax: the surface
// A x^2 + B y^2 + C z^2 + D xy + E xz + F yz + G x + H y + I z + J = 0
// (POV-Ray's order) inside the box. Stored about the box's float centre,
// with a half-extent rounded up (the stored box holds the given one), and
// scaled by a power of two so that its largest term over the box is about 1.
bool ParseNff(PrimTag<Quadric>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "quadric") return false;
  double k[10];
  const char* names = "ABCDEFGHIJ";
  for (int i = 0; i < 10; ++i) k[i] = st.Number(fmt::format("coefficient {}", names[i]).c_str());
  const glm::dvec3 lo = st.Vec("a clip box min coordinate");
  const glm::dvec3 hi = st.Vec("a clip box max coordinate");
  const char* axes = "xyz";
  for (int a = 0; a < 3; ++a)
    if (!(lo[a] < hi[a]))
      st.Fail(fmt::format("'quadric': clip box {}min {} is not less than {}max {} (the box must have volume)",
                          axes[a], lo[a], axes[a], hi[a]));
  bool any = false;
  for (int i = 0; i < 9; ++i) any = any || k[i] != 0.0;
  if (!any) st.Fail("'quadric': coefficients A to I are all 0 (no surface)");
  Quadric s{};
  glm::dvec3 m, h;
  for (int a = 0; a < 3; ++a) {
    s.center[a] = float(0.5 * (lo[a] + hi[a]));
    m[a] = double(s.center[a]);
    s.extent[a] = FloatUp(std::max(hi[a] - m[a], m[a] - lo[a]));
    h[a] = double(s.extent[a]);
  }
  // Q (symmetric), L / 2, J about m: f(m + x) = x Q x + 2 (Q m + L / 2) x + f(m).
  const double Q[3][3] = {{k[0], k[3] / 2, k[4] / 2}, {k[3] / 2, k[1], k[5] / 2}, {k[4] / 2, k[5] / 2, k[2]}};
  const double L[3] = {k[6], k[7], k[8]};
  double l[3], j = k[9];
  for (int i = 0; i < 3; ++i) {
    l[i] = L[i] / 2;
    for (int c = 0; c < 3; ++c) l[i] += Q[i][c] * m[c];
    double qm = 0.0;
    for (int c = 0; c < 3; ++c) qm += Q[i][c] * m[c];
    j += m[i] * qm + L[i] * m[i];
  }
  // Scale: the largest term over the box to about 1, by a power of two.
  double big = std::fabs(j);
  for (int i = 0; i < 3; ++i) {
    big = std::max(big, 2.0 * std::fabs(l[i]) * h[i]);
    for (int c = 0; c < 3; ++c) big = std::max(big, std::fabs(Q[i][c]) * h[i] * h[c]);
  }
  const double scale = big > 0.0 && std::isfinite(big) ? std::ldexp(1.0, -std::ilogb(big)) : 1.0;
  const int idx[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (int e = 0; e < 6; ++e) s.q[e] = float(Q[idx[e][0]][idx[e][1]] * scale);
  for (int i = 0; i < 3; ++i) s.l[i] = float(l[i] * scale);
  s.j = float(j * scale);
  // q[6] and l[3] lie back to back in the layout.
  if (!std::isfinite(s.j) || !std::all_of(&s.q[0], &s.q[0] + 9, [](float v) { return std::isfinite(v); }))
    st.Fail("'quadric': a coefficient overflows float about the clip box's centre");
  PrimInfo info = st.Info(CR_PRIM_QUADRIC);
  info.firstPiece = scene.AddPiece(s, scene.NumPrims());
  info.nPieces = 1;
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
