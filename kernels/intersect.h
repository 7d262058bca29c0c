/* Ray-primitive intersection, shared by every structure and backend.
 *
 * Precision modes (macros):
 *   default  `robust`: watertight triangles (Woop, Benthin & Wald 2013), the
 *            stable sphere quadratic (Hearn & Baker 14-6; Haines et al., Ray
 *            Tracing Gems ch. 7: the discriminant from |f x d|, the roots as
 *            q/a and c/q), conservative slab tests (Ize 2013);
 *   CR_FAST  `fast`: Moller-Trumbore with a fixed determinant epsilon, the
 *            textbook quadratic, plain slab tests;
 *   CR_FP64  `fp64`: the robust algorithms with real = double.
 * Model only what the scene needs: CR_HAS_SPHERES / CR_HAS_TRIANGLES /
 * CR_HAS_CONES (default 1) remove the code of absent primitive types. */
#ifndef CELLRAY_KERNELS_INTERSECT_H
#define CELLRAY_KERNELS_INTERSECT_H
#include "ray.h"

#ifndef CR_HAS_SPHERES
#define CR_HAS_SPHERES 1
#endif
#ifndef CR_HAS_TRIANGLES
#define CR_HAS_TRIANGLES 1
#endif
#ifndef CR_HAS_CONES
#define CR_HAS_CONES 1
#endif

/* The primitive arrays of a scene, unified index g as in types.h. */
typedef struct {
  CR_GLOBAL const Sphere* spheres;
  CR_GLOBAL const Triangle* triangles;
  CR_GLOBAL const Cone* cones;
  PrimRanges ranges;
} PrimView;

/* Roots of a t^2 + 2 bh t + c = 0 given disc = bh^2 - a c >= 0, smaller first
 * (Press et al.: q = -(bh + sign(bh) sqrt(disc)), roots q/a and c/q, no
 * cancellation between -bh and the square root). The Vieta root c/q is only
 * as good as c, which is itself a difference (|f|^2 - r^2: it cancels when
 * the origin is near the surface) with an error of about eps * cScale; when
 * q is tiny too (a nearly tangent ray from near the surface) c/q is noise,
 * a "root" anywhere along the ray. Its error eps cScale / |q| is then
 * compared with the error eps |q| / a of the direct form (sqrt - bh) / a,
 * and the smaller wins (with a margin of 16 in favour of Vieta). */
CR_FUNC void Quadratic_Roots(real a, real bh, real c, real cScale, real disc, real* t0, real* t1, real* qOut)
{
  real sq = copysign(sqrt(disc), bh);
  real q = -(bh + sq);
  *qOut = q;
  real r0 = q / a;
  real r1 = ((real)16.0f * q * q >= a * cScale) ? c / q : (sq - bh) / a;
  *t0 = fmin(r0, r1);
  *t1 = fmax(r0, r1);
}

#if !defined(CR_FAST) && !defined(CR_FP64)
/* Error-free transformations in float (Knuth's TwoSum; Dekker's TwoProduct
 * with Veltkamp's split, which needs no FMA, so every device gets the same
 * bits): a + b = s + e and a b = p + e exactly. */
CR_FUNC float Ef_TwoSum(float a, float b, float* e)
{
  const float s = a + b;
  const float bb = s - a;
  *e = (a - (s - bb)) + (b - bb);
  return s;
}
CR_FUNC float Ef_TwoProduct(float a, float b, float* e)
{
  const float p = a * b;
  const float ca = 4097.0f * a, cb = 4097.0f * b;
  const float ah = ca - (ca - a), bh = cb - (cb - b);
  const float al = a - ah, bl = b - bh;
  *e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
  return p;
}
/* a b - c d to a few ulps even when the two products cancel. */
CR_FUNC float Ef_DiffOfProducts(float a, float b, float c, float d)
{
  float e1, e2, es;
  const float p1 = Ef_TwoProduct(a, b, &e1);
  const float p2 = Ef_TwoProduct(c, d, &e2);
  const float s = Ef_TwoSum(p1, -p2, &es);
  return s + (es + (e1 - e2));
}

/* The sphere's |f x d|^2 in float carries two errors: the products that
 * cancel in each component (about u |f| |d| each), and f = o - c itself,
 * rounded to the spacing of the larger coordinate (origin detail finer than
 * that is lost: a camera jittered by 1e-4 looking at a sphere 1e4 away).
 * Where |disc| is within a bound E of those errors its sign, hit or miss, is
 * not decided, and Sphere_IntersectDf recomputes the whole test in
 * double-float from the exact o - c (fh + fl, TwoSum).
 * E ~ 3 sqrt(3) u |f| |d| (|f x d| + 3 u |f| |d|) + u a r^2, compared
 * squared so that no square root is needed, with a factor of 8 to spare:
 * E^2 <= 2^-29 P (cc + 2^-38 P), P = |f|^2 |d|^2 (the a r^2 term is absorbed:
 * a r^2 = disc + cc). With Q = 2^-29 P: disc^2 <= Q (cc + 2^-9 Q). Overflow
 * only errs towards the exact path. Below -2^15 Q (= -2^-14 P) disc is a
 * certain miss, found before the bound (most tests end there). */
CR_FUNC int Sphere_DiscUndecided(real disc, real Q, real cc) { return disc * disc <= Q * (cc + 0x1.0p-9f * Q); }
/* a r^2 - |f x d|^2 with f = fh + fl exact: each component of the cross
 * product from exact products (Ef_DiffOfProducts) plus the small fl terms. */
CR_FUNC real Sphere_DiscOfExactF(const real fh[3], const real fl[3], const real d[3], real ar2)
{
  const real cx = Ef_DiffOfProducts(fh[1], d[2], fh[2], d[1]) + (fl[1] * d[2] - fl[2] * d[1]);
  const real cy = Ef_DiffOfProducts(fh[2], d[0], fh[0], d[2]) + (fl[2] * d[0] - fl[0] * d[2]);
  const real cz = Ef_DiffOfProducts(fh[0], d[1], fh[1], d[0]) + (fl[0] * d[1] - fl[1] * d[0]);
  return ar2 - (cx * cx + cy * cy + cz * cz);
}

/* |a| >= |b| (or a == 0): a + b = s + e exactly. */
CR_FUNC float Ef_FastTwoSum(float a, float b, float* e)
{
  const float s = a + b;
  *e = b - (s - a);
  return s;
}

/* The distance to sphere s that its float test reports (the nearer root,
 * or the farther when the nearer lies before tmin) as a double-float
 * hi + lo, for ordering two spheres whose float distances tie exactly: two
 * surfaces closer along the ray than one ulp of t. f = o - c is exact
 * (fh + fl), bh = f.d and a = d.d are summed from exact products, and the
 * roots (-bh -+ sq) / a are divided in double-float. sq, the square root of
 * Sphere_DiscOfExactF, stays float: its error is u sq, and at a tie between two
 * surfaces of small far spheres sq is far below |bh|. */
CR_FUNC void Sphere_TieT(const real org[3], const real dir[3], real tmin, const Sphere* s, real* hi, real* lo)
{
  real fh[3], fl[3];
  real bhH = 0.0f, bhL = 0.0f, aH = 0.0f, aL = 0.0f;
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    fh[i] = Ef_TwoSum(org[i], -s->center[i], &fl[i]);
    real e, se;
    real p = Ef_TwoProduct(fh[i], dir[i], &e);
    bhH = Ef_TwoSum(bhH, p, &se);
    bhL = bhL + (se + (e + fl[i] * dir[i]));
    p = Ef_TwoProduct(dir[i], dir[i], &e);
    aH = Ef_TwoSum(aH, p, &se);
    aL = aL + (se + e);
  }
  bhH = Ef_FastTwoSum(bhH, bhL, &bhL);
  aH = Ef_FastTwoSum(aH, aL, &aL);
  const real disc = Sphere_DiscOfExactF(fh, fl, dir, aH * s->radius * s->radius);
  const real sq = disc > 0.0f ? CR_SQRTF(disc) : 0.0f;
  real nL, qL, pe;
  for (int root = 0; root < 2; ++root) {
    /* numerator -bh -+ sq, then the quotient by a */
    real nH = Ef_TwoSum(-bhH, root == 0 ? -sq : sq, &nL);
    nL = nL - bhL;
    nH = Ef_FastTwoSum(nH, nL, &nL);
    const real qH = nH / aH;
    const real p = Ef_TwoProduct(qH, aH, &pe);
    qL = ((((nH - p) - pe) + nL) - qH * aL) / aH;
    *hi = Ef_FastTwoSum(qH, qL, lo);
    if (*hi >= tmin) return;
  }
}

/* Order of spheres a and b along the ray at a float tie: -1 when a's surface
 * comes first, 1 when b's, 0 when not even double-float tells them apart. */
CR_COLD CR_FUNC int Sphere_TieOrder(const real org[3], const real dir[3], real tmin, const Sphere* a, const Sphere* b)
{
  real ah, al, bh, bl;
  Sphere_TieT(org, dir, tmin, a, &ah, &al);
  Sphere_TieT(org, dir, tmin, b, &bh, &bl);
  if (ah != bh) return ah < bh ? -1 : 1;
  if (al != bl) return al < bl ? -1 : 1;
  return 0;
}

/* Double-float arithmetic: a value hi + lo with |lo| <= ulp(hi) / 2, about
 * 48 bits, built from the error-free transformations above, so every device
 * and the SIMD backend get the same bits. Used where float cannot give t to
 * a few ulps: huge primitives seen from nearby (a sphere of radius 1e6 used
 * as a ground: |f|^2 - r^2 loses 16 bits; a triangle 1e6 across: its
 * vertices lie 5e5 from a hit 100 away). Each operation is written so that
 * swapping its operands gives the same bits (the watertight edge functions
 * rely on Cx By - Cy Bx being the exact negation of By Cx - Bx Cy). */
typedef struct {
  float hi;
  float lo;
} Df;
CR_FUNC Df Df_Norm(float s, float e)
{
  Df r;
  r.hi = Ef_FastTwoSum(s, e, &r.lo);
  return r;
}
CR_FUNC Df Df_F(float a)
{
  Df r;
  r.hi = a;
  r.lo = 0.0f;
  return r;
}
CR_FUNC Df Df_Neg(Df a)
{
  a.hi = -a.hi;
  a.lo = -a.lo;
  return a;
}
/* a + b and a b of two floats, exactly. */
CR_FUNC Df Df_SumF(float a, float b)
{
  Df r;
  r.hi = Ef_TwoSum(a, b, &r.lo);
  return r;
}
CR_FUNC Df Df_ProdF(float a, float b)
{
  Df r;
  r.hi = Ef_TwoProduct(a, b, &r.lo);
  return r;
}
CR_FUNC Df Df_Add(Df a, Df b)
{
  float e;
  const float s = Ef_TwoSum(a.hi, b.hi, &e);
  return Df_Norm(s, e + (a.lo + b.lo));
}
CR_FUNC Df Df_Sub(Df a, Df b) { return Df_Add(a, Df_Neg(b)); }
CR_FUNC Df Df_Mul(Df a, Df b)
{
  float e;
  const float p = Ef_TwoProduct(a.hi, b.hi, &e);
  return Df_Norm(p, e + (a.hi * b.lo + a.lo * b.hi));
}
CR_FUNC Df Df_MulF(Df a, float b)
{
  float e;
  const float p = Ef_TwoProduct(a.hi, b, &e);
  return Df_Norm(p, e + a.lo * b);
}
CR_FUNC Df Df_Div(Df a, Df b)
{
  const float q1 = a.hi / b.hi;
  const Df r = Df_Sub(a, Df_MulF(b, q1));
  return Df_Norm(q1, r.hi / b.hi);
}
CR_FUNC Df Df_Sqrt(Df a)
{
  if (!(a.hi > 0.0f)) return Df_F(0.0f);
  const float s = CR_SQRTF(a.hi);
  float e;
  const float p = Ef_TwoProduct(s, s, &e);
  return Df_Norm(s, (((a.hi - p) - e) + a.lo) / (2.0f * s));
}
/* a x b and a . b of vectors held as double-floats. */
CR_FUNC Df Df_Dot3(const Df a[3], const Df b[3])
{
  return Df_Add(Df_Add(Df_Mul(a[0], b[0]), Df_Mul(a[1], b[1])), Df_Mul(a[2], b[2]));
}
CR_FUNC Df Df_Dot3F(const Df a[3], const real b[3])
{
  return Df_Add(Df_Add(Df_MulF(a[0], b[0]), Df_MulF(a[1], b[1])), Df_MulF(a[2], b[2]));
}
CR_FUNC void Df_Cross(const Df a[3], const Df b[3], Df c[3])
{
  c[0] = Df_Sub(Df_Mul(a[1], b[2]), Df_Mul(a[2], b[1]));
  c[1] = Df_Sub(Df_Mul(a[2], b[0]), Df_Mul(a[0], b[2]));
  c[2] = Df_Sub(Df_Mul(a[0], b[1]), Df_Mul(a[1], b[0]));
}
/* Roots of a t^2 + 2 bh t + c = 0 in double-float given disc >= 0, as float
 * (the nearest float to hi + lo is hi), smaller first. */
CR_FUNC void Df_QuadraticRoots(Df a, Df bh, Df c, Df disc, real* t0, real* t1)
{
  Df sq = Df_Sqrt(disc);
  if (bh.hi < 0.0f) sq = Df_Neg(sq);
  const Df q = Df_Neg(Df_Add(bh, sq));
  const real r0 = Df_Div(q, a).hi;
  const real r1 = q.hi != 0.0f ? Df_Div(c, q).hi : r0;
  *t0 = fmin(r0, r1);
  *t1 = fmax(r0, r1);
}

/* When the float roots of Sphere_Intersect may be off by more than a few
 * ulps, and one of them may lie in [tmin, tmax]. Off: c cancels (cScale > 8
 * |c|: the origin near the surface relative to its distance from the centre,
 * as under a ground sphere), or q = -(bh +- sqrt(disc)) carries the error of a
 * discriminant that cancels (dScale > 8 sqrt(disc) (|bh| + sqrt(disc)),
 * compared squared, conservatively, without the root; always redone past
 * 2^18 times that measure). May lie in range: each root within its own
 * window, so that a ray leaving the surface (c cancels, one root near 0) is
 * redone only when that near root may lie in range, never because the other
 * root is far away. The windows, to first order, generously (u = 2^-24):
 * - disc = a r^2 - cc is off by at most 8u sqrt(a ff cc) (the cross product's
 *   components cancel) + 6u dScale, its root by that over 2 sqrt(disc); bh
 *   by 5u sqrt(a ff); so q by eq below, and relatively by rel;
 * - the root q / a is within rel of itself; c / q too, plus c's error (6u
 *   cScale) over |q|: e; where Quadratic_Roots takes (sq - bh) / a instead
 *   (16 q^2 < a cScale) that root carries eq / a, rel of the other root, so
 *   both windows take the larger root's share (m).
 * First order holds: disc's error is below a quarter of disc wherever this
 * is reached (Sphere_DiscUndecided and the 2^36 rule took the rest). */
CR_FUNC int Sphere_NeedsDf(real c, real cScale, real bh, real disc, real dScale, real q, real a, real ff, real cc,
                           real t0, real t1, real tmin, real tmax)
{
  const real dd = disc * (bh * bh + disc);
  const real ds2 = dScale * dScale;
  if (!(cScale > 8.0f * fabs(c) || ds2 > 64.0f * dd)) return 0;
  if (ds2 > 0x1.0p36f * dd || !(disc > (real)0.0f)) return 1;
  const real af = a * ff;
  const real eq = 0x1.0p-20f * ((sqrt(af * cc) + dScale) / sqrt(disc) + sqrt(af));
  const real rel = eq / fabs(q) + 0x1.0p-20f;
  const real e = 0x1.0p-18f * cScale / fabs(q);
  const real m = (real)16.0f * q * q >= a * cScale ? (real)0.0f : fmax(fabs(t0), fabs(t1));
  const real s0 = rel * fmax(fabs(t0), m) + e, s1 = rel * fmax(fabs(t1), m) + e;
  return (t0 + s0 >= tmin && t0 - s0 <= tmax) || (t1 + s1 >= tmin && t1 - s1 <= tmax);
}
/* Sphere_NeedsDf's rule for a cone (Cone_Intersect), or o - base much longer than its radial part
 * oR (a long cone seen from beside its middle: oR carries the rounding of
 * o - base, relatively |dl| / |oR| ulps; always redone past 2^18). Then C's
 * error grows with |dl| too: about 22 ulps of |oR| |dl| + 8 of |k rb| |dl|,
 * which e bounds (2^-18 = 64 ulps) with cScale's share. Each root gets its
 * own window, rel of itself plus e / |q|, rel bounding q's and A's relative
 * errors (below; always redone past 1/16): a ray leaving the cone's surface
 * is redone only when its near root may lie in range, not because the far
 * root is large. Where the other root is (sq - bh) / A, it carries q's error
 * divided by A: both windows then take the larger root's share, as for
 * Sphere_NeedsDf. */
CR_FUNC int Cone_NeedsDf(real C, real cScale, real Bh, real disc, real ee, real xx, real q, real dl2, real oo, real k,
                         real ds, real rb, real dRdR, real dd, real A, real t0, real t1, real tmin, real tmax)
{
  const real dScale = ee + xx;
  const real d2 = disc * (Bh * Bh + disc);
  if (!(cScale > 8.0f * fabs(C) || dScale * dScale > 64.0f * d2 || dl2 > 64.0f * oo)) return 0;
  if (dScale * dScale > 0x1.0p36f * d2 || dl2 > 0x1.0p36f * oo || !(disc > (real)0.0f)) return 1;
  const real ndl = sqrt(dl2), ndR = sqrt(dRdR), nd = sqrt(dd), noR = sqrt(oo), kds = fabs(k * ds);
  /* First-order bounds (u = 2^-24, generously): oR within 11u |dl|, dR
   * within 6u |d|, rb within 4u |k| |dl| + 2u |rb|; so e = rb dR - k ds oR
   * within Ee, x = oR x dR within Ex, disc = ee - xx within eDisc, Bh within
   * eB, A within eA; q within eq, its root's share relative to |q|. */
  const real Ee = 0x1.0p-20f * ((fabs(k) * ndl + fabs(rb)) * ndR + fabs(rb) * nd + kds * ndl);
  const real Ex = 0x1.0p-19f * (ndl * ndR + noR * nd);
  const real eDisc = 2.0f * (sqrt(ee) * Ee + sqrt(xx) * Ex) + 0x1.0p-21f * dScale;
  const real eB = 0x1.0p-20f * (ndl * (ndR + fabs(k) * kds) + noR * nd + kds * fabs(rb));
  const real eA = 0x1.0p-19f * (ndR * nd + kds * kds + fabs(k) * kds * nd);
  const real eq = eDisc / (2.0f * sqrt(disc)) + eB;
  const real rel = eq / fabs(q) + eA / fabs(A) + 0x1.0p-20f;
  if (!(eDisc < 0.25f * disc && rel < 0.0625f)) return 1;
  const real e = 0x1.0p-18f * (cScale + ndl * (noR + fabs(k * rb))) / fabs(q);
  const real m = (real)16.0f * q * q >= A * cScale ? (real)0.0f : fmax(fabs(t0), fabs(t1));
  const real s0 = rel * fmax(fabs(t0), m) + e, s1 = rel * fmax(fabs(t1), m) + e;
  return (t0 + s0 >= tmin && t0 - s0 <= tmax) || (t1 + s1 >= tmin && t1 - s1 <= tmax);
}

/* Sphere_Intersect in double-float from the exact o - c: the cold path for
 * Sphere_NeedsDf. Returns 1 with the root in [tmin, tmax] nearest. */
CR_COLD CR_FUNC int Sphere_IntersectDf(const real org[3], const real dir[3], const Sphere* s, real tmin, real tmax,
                                       real* tHit)
{
  Df f[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) f[i] = Df_SumF(org[i], -s->center[i]);
  const Df a = Df_Add(Df_Add(Df_ProdF(dir[0], dir[0]), Df_ProdF(dir[1], dir[1])), Df_ProdF(dir[2], dir[2]));
  const Df bh = Df_Dot3F(f, dir);
  const Df r2 = Df_ProdF(s->radius, s->radius);
  const Df c = Df_Sub(Df_Dot3(f, f), r2);
  Df x[3];
  x[0] = Df_Sub(Df_MulF(f[1], dir[2]), Df_MulF(f[2], dir[1]));
  x[1] = Df_Sub(Df_MulF(f[2], dir[0]), Df_MulF(f[0], dir[2]));
  x[2] = Df_Sub(Df_MulF(f[0], dir[1]), Df_MulF(f[1], dir[0]));
  const Df disc = Df_Sub(Df_Mul(a, r2), Df_Dot3(x, x));
  if (disc.hi < 0.0f) return 0;
  real t0, t1;
  Df_QuadraticRoots(a, bh, c, disc, &t0, &t1);
  if (t0 >= tmin && t0 <= tmax) {
    *tHit = t0;
    return 1;
  }
  if (t1 >= tmin && t1 <= tmax) {
    *tHit = t1;
    return 1;
  }
  return 0;
}

/* The distance to the triangle's plane in double-float, from the exact edges
 * v1 - v0, v2 - v0 and the exact v0 - o: the cold path of Triangle_Intersect
 * when n . p cancels (a vertex far from the ray origin relative to the
 * plane's distance: a huge triangle seen from nearby, or a grazing view). */
CR_COLD CR_FUNC real Triangle_PlaneTDf(const real org[3], const real dir[3], const Triangle* tri)
{
  Df e1[3], e2[3], p[3], n[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    e1[i] = Df_SumF(tri->v1[i], -tri->v0[i]);
    e2[i] = Df_SumF(tri->v2[i], -tri->v0[i]);
    p[i] = Df_SumF(tri->v0[i], -org[i]);
  }
  Df_Cross(e1, e2, n);
  const Df nd = Df_Dot3F(n, dir);
  if (nd.hi == 0.0f) return CR_INF;
  return Df_Div(Df_Dot3(n, p), nd).hi;
}
/* Whether Triangle_Intersect's float t (n . p / nd from the products np)
 * needs Triangle_PlaneTDf: n . p cancels by more than 16 (the shared vertex
 * far from the origin relative to the plane's distance: a huge triangle seen
 * from nearby, or a grazing view), and t may lie in [tmin, tmax]: widened by
 * a quarter of t and by the dot product's own error over nd (2^-20 of the
 * sum of the products' magnitudes, generously), which keeps a ray leaving a
 * triangle (t slightly negative, n . p cancelling completely) on the float
 * path. */
CR_FUNC int Triangle_PlaneInexact(real np0, real np1, real np2)
{
  return (fabs(np0) + fabs(np1)) + fabs(np2) > 16.0f * fabs((np0 + np1) + np2);
}
CR_FUNC int Triangle_PlaneNeedsDf(real np0, real np1, real np2, real nd, real t, real tmin, real tmax)
{
  const real sum = (fabs(np0) + fabs(np1)) + fabs(np2);
  if (!(sum > 16.0f * fabs((np0 + np1) + np2))) return 0;
  const real slack = 0.25f * fabs(t) + 0x1.0p-20f * sum / fabs(nd);
  return t + slack >= tmin && t - slack <= tmax;
}

/* One watertight edge function P'x Q'y - P'y Q'x of the vertices p, q
 * (world coordinates) translated to the ray origin and sheared, in
 * double-float from the exact p - o, q - o. Swapping p and q gives the exact
 * negation, as in float, so the two triangles sharing the edge still agree. */
CR_FUNC Df Triangle_ShearDf(const Ray* r, const real v[3], int axis)
{
  const Df tz = Df_SumF(CR_PICK3(v, r->kz), -CR_PICK3(r->org, r->kz));
  const Df ta = Df_SumF(CR_PICK3(v, axis), -CR_PICK3(r->org, axis));
  return Df_Sub(ta, Df_MulF(tz, axis == r->kx ? r->sx : r->sy));
}
CR_FUNC real Triangle_EdgeDf(const Ray* r, const real p[3], const real q[3])
{
  const Df px = Triangle_ShearDf(r, p, r->kx), py = Triangle_ShearDf(r, p, r->ky);
  const Df qx = Triangle_ShearDf(r, q, r->kx), qy = Triangle_ShearDf(r, q, r->ky);
  return Df_Sub(Df_Mul(px, qy), Df_Mul(py, qx)).hi;
}
/* L1 norm of a translated vertex v - o (its components in the ray's axis
 * order kx, ky, kz): the scale of the rounding of its sheared coordinates
 * (|sx|, |sy| <= 1: kz is the dominant axis). */
CR_FUNC real Triangle_Norm1(real x, real y, real z) { return (fabs(x) + fabs(y)) + fabs(z); }
/* All three edge functions in double-float (Triangle_Intersect's cold path
 * for a degenerate projection). */
CR_COLD CR_FUNC void Triangle_EdgesDf(const Ray* r, const Triangle* tri, real* U, real* V, real* W)
{
  real v0[3], v1[3], v2[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    v0[i] = tri->v0[i];
    v1[i] = tri->v1[i];
    v2[i] = tri->v2[i];
  }
  *U = Triangle_EdgeDf(r, v2, v1);
  *V = Triangle_EdgeDf(r, v0, v2);
  *W = Triangle_EdgeDf(r, v1, v0);
}
/* Whether all three float edge functions lie within their rounding error,
 * 2^-19 times the product of their vertices' translated L1 norms (the bound
 * of Triangle_RefineEdges with a margin of 2 instead of 4). Arguments: the
 * translated vertices in the ray's axis order (kx, ky, kz). */
CR_FUNC int Triangle_EdgesUndecided(real nA, real nB, real nC, real U, real V, real W)
{
  return fabs(U) <= 0x1.0p-19f * (nB * nC) && fabs(V) <= 0x1.0p-19f * (nC * nA) && fabs(W) <= 0x1.0p-19f * (nA * nB);
}

/* The float edge functions U, V, W of a triangle with long edges (flags
 * CR_TRI_LONG_*: longer than 16 times their distance from the world origin,
 * where float's error, relative to |v - o|, can exceed check.h's tolerance,
 * relative to |o| + t |d|): a flagged edge whose value lies within its
 * rounding error of 0, 2^-18 |P - o|_1 |Q - o|_1 (translation, shear and
 * products each err by a few u times these magnitudes; nA, nB, nC are the
 * vertices' norms, Triangle_Norm1), is recomputed in double-float. An edge's
 * flag, bound and value depend on the edge alone, so both triangles sharing
 * it decide alike and the test stays watertight. */
CR_FUNC int Triangle_LongEdgeUndecided(uint flags, real nA, real nB, real nC, real U, real V, real W)
{
  return ((flags & CR_TRI_LONG_U) && fabs(U) <= 0x1.0p-18f * (nB * nC)) ||
         ((flags & CR_TRI_LONG_V) && fabs(V) <= 0x1.0p-18f * (nC * nA)) ||
         ((flags & CR_TRI_LONG_W) && fabs(W) <= 0x1.0p-18f * (nA * nB));
}
CR_COLD CR_FUNC void Triangle_RefineEdges(const Ray* r, const Triangle* tri, real nA, real nB, real nC, real* U,
                                          real* V, real* W)
{
  real v0[3], v1[3], v2[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    v0[i] = tri->v0[i];
    v1[i] = tri->v1[i];
    v2[i] = tri->v2[i];
  }
  if ((tri->flags & CR_TRI_LONG_U) && fabs(*U) <= 0x1.0p-18f * (nB * nC)) *U = Triangle_EdgeDf(r, v2, v1);
  if ((tri->flags & CR_TRI_LONG_V) && fabs(*V) <= 0x1.0p-18f * (nC * nA)) *V = Triangle_EdgeDf(r, v0, v2);
  if ((tri->flags & CR_TRI_LONG_W) && fabs(*W) <= 0x1.0p-18f * (nA * nB)) *W = Triangle_EdgeDf(r, v1, v0);
}

/* Cone_Intersect in double-float from the exact apex - base and o - base:
 * the cold path for Cone_NeedsDf (a cylinder of radius 1e6 as a ground,
 * a cone 1e6 long seen from 100 away). Same formulas as the float test. */
CR_COLD CR_FUNC int Cone_IntersectDf(const real org[3], const real dir[3], const Cone* cn, real tmin, real tmax,
                                     real* tHit)
{
  Df w[3], dl[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    w[i] = Df_SumF(cn->apex[i], -cn->base[i]);
    dl[i] = Df_SumF(org[i], -cn->base[i]);
  }
  const Df H = Df_Sqrt(Df_Dot3(w, w));
  if (!(H.hi > 0.0f)) return 0;
  CR_UNROLL for (int i = 0; i < 3; ++i) w[i] = Df_Div(w[i], H);
  const Df r0 = Df_F(cn->baseRadius);
  const Df k = Df_Div(Df_SumF(cn->apexRadius, -cn->baseRadius), H);
  const Df ds = Df_Dot3F(w, dir);
  const Df os = Df_Dot3(dl, w);
  Df dR[3], oR[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    dR[i] = Df_Sub(Df_F(dir[i]), Df_Mul(ds, w[i]));
    oR[i] = Df_Sub(dl[i], Df_Mul(os, w[i]));
  }
  const Df rb = Df_Add(r0, Df_Mul(k, os));
  const Df kds = Df_Mul(k, ds);
  const Df A = Df_Sub(Df_Dot3(dR, dR), Df_Mul(kds, kds));
  const Df Bh = Df_Sub(Df_Dot3(oR, dR), Df_Mul(kds, rb));
  const Df C = Df_Sub(Df_Dot3(oR, oR), Df_Mul(rb, rb));
  real t0, t1;
  if (A.hi == 0.0f) {
    if (Bh.hi == 0.0f) return 0;
    t0 = t1 = Df_Div(Df_Neg(C), Df_MulF(Bh, 2.0f)).hi;
  } else {
    Df e[3], x[3];
    CR_UNROLL for (int i = 0; i < 3; ++i) e[i] = Df_Sub(Df_Mul(rb, dR[i]), Df_Mul(kds, oR[i]));
    Df_Cross(oR, dR, x);
    const Df disc = Df_Sub(Df_Dot3(e, e), Df_Dot3(x, x));
    if (disc.hi < 0.0f) return 0;
    Df_QuadraticRoots(A, Bh, C, disc, &t0, &t1);
  }
  for (int root = 0; root < 2; ++root) {
    const real t = root == 0 ? t0 : t1;
    if (!(t >= tmin && t <= tmax)) continue;
    const Df sx = Df_Add(os, Df_MulF(ds, t));
    if (sx.hi >= 0.0f && Df_Sub(sx, H).hi <= 0.0f) {
      *tHit = t;
      return 1;
    }
  }
  return 0;
}
#endif

/* Hit_Closer for primitive g met at t by ray r, with one refinement in
 * robust mode: an exact float tie between two different spheres goes to the
 * one that double-float arithmetic finds nearer (Sphere_TieOrder); any
 * other tie to the lower id. */
CR_FUNC int Hit_CloserOn(const PrimView* pv, const Ray* r, real t, uint g, const Hit* h)
{
#if CR_HAS_SPHERES && !defined(CR_FAST) && !defined(CR_FP64)
  if (t == h->t && g != h->g && Prim_Is(&pv->ranges, CR_PRIM_SPHERE, g) && Prim_Is(&pv->ranges, CR_PRIM_SPHERE, h->g)) {
    const Sphere a = pv->spheres[g];
    const Sphere b = pv->spheres[h->g];
    const int order = Sphere_TieOrder(r->org, r->dir, r->tmin, &a, &b);
    if (order != 0) return order < 0;
  }
#endif
  return Hit_Closer(t, g, h);
}

/* The typed tests take the primitive in private memory (a copy), so that a
 * caller may hold it anywhere: global memory (Prim_Intersect), or local
 * memory shared by a work-group (kernels/bvh_packet.cl). */

/* Sphere: nearest root in [tmin, tmax]. */
CR_FUNC int Sphere_Intersect(const Ray* r, const Sphere* s, real tmin, real tmax, real* tHit)
{
  real f[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) f[i] = r->org[i] - (real)s->center[i];
  real rad = (real)s->radius;
  real a = Dot3(r->dir, r->dir);
  real bh = Dot3(f, r->dir);
  real ff = Dot3(f, f);
  real c = ff - rad * rad;
  real t0, t1;
#ifdef CR_FAST
  real b = (real)2.0f * bh;
  real disc4 = b * b - (real)4.0f * a * c;
  if (disc4 < (real)0.0f) return 0;
  real sq = sqrt(disc4);
  t0 = (-b - sq) / ((real)2.0f * a);
  t1 = (-b + sq) / ((real)2.0f * a);
#else
  /* bh^2 - a c = a r^2 - |f x d|^2: the squared distance of the centre from
   * the ray's line comes from a cross product, exact in the cases where the
   * textbook form cancels (small far spheres, rays through the centre). */
  real cx = f[1] * r->dir[2] - f[2] * r->dir[1];
  real cy = f[2] * r->dir[0] - f[0] * r->dir[2];
  real cz = f[0] * r->dir[1] - f[1] * r->dir[0];
  real ar2 = a * rad * rad;
  real cc = cx * cx + cy * cy + cz * cz;
  real disc = ar2 - cc;
#ifndef CR_FP64
  const real Q = 0x1.0p-29f * (ff * a);
  if (disc < -0x1.0p15f * Q) return 0;
  /* Hit or miss not decided by float: double-float from the exact o - c. */
  if (Sphere_DiscUndecided(disc, Q, cc)) return Sphere_IntersectDf(r->org, r->dir, s, tmin, tmax, tHit);
#endif
  if (disc < (real)0.0f) return 0;
  real q;
  Quadratic_Roots(a, bh, c, ff + rad * rad, disc, &t0, &t1, &q);
#ifndef CR_FP64
  if (Sphere_NeedsDf(c, ff + rad * rad, bh, disc, ar2 + cc, q, a, ff, cc, t0, t1, tmin, tmax))
    return Sphere_IntersectDf(r->org, r->dir, s, tmin, tmax, tHit);
#endif
#endif
  if (t0 >= tmin && t0 <= tmax) {
    *tHit = t0;
    return 1;
  }
  if (t1 >= tmin && t1 <= tmax) {
    *tHit = t1;
    return 1;
  }
  return 0;
}

/* The normal of the triangle's plane for the robust distance (see
 * Triangle_Intersect): the cross product of the shortest edge and the next
 * one, edges from the stored vertices (differences of vertices translated to
 * the ray origin would carry |v - o| rounding). Returns the index of the
 * vertex the two edges share (0, 1, 2: v0, v1, v2). */
CR_FUNC int Triangle_PlaneNormal(const Triangle* tri, real n[3])
{
  real e[9];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    e[i] = (real)tri->v1[i] - (real)tri->v0[i];
    e[3 + i] = (real)tri->v2[i] - (real)tri->v1[i];
    e[6 + i] = (real)tri->v0[i] - (real)tri->v2[i];
  }
  const real l0 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  const real l1 = e[3] * e[3] + e[4] * e[4] + e[5] * e[5];
  const real l2 = e[6] * e[6] + e[7] * e[7] + e[8] * e[8];
  /* k: the shortest edge; k1: its successor. */
  const int k = (l0 <= l1) ? ((l0 <= l2) ? 0 : 2) : ((l1 <= l2) ? 1 : 2);
  const int k1 = k == 2 ? 0 : k + 1;
  real ea[3], eb[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    /* selects, not e[3 * k + i]: an array indexed by a computed value stays
     * in memory and keeps PoCL from vectorising the packet kernels' test */
    ea[i] = k == 0 ? e[i] : (k == 1 ? e[3 + i] : e[6 + i]);
    eb[i] = k1 == 0 ? e[i] : (k1 == 1 ? e[3 + i] : e[6 + i]);
  }
  n[0] = ea[1] * eb[2] - ea[2] * eb[1];
  n[1] = ea[2] * eb[0] - ea[0] * eb[2];
  n[2] = ea[0] * eb[1] - ea[1] * eb[0];
  return k1;
}

/* Triangle: t and barycentrics (u weights v1, v weights v2). */
CR_FUNC int Triangle_Intersect(const Ray* r, const Triangle* tri, real tmin, real tmax, real* tHit,
                               real* uHit, real* vHit)
{
#ifdef CR_FAST
  /* Moller & Trumbore 1997, fixed epsilon on the determinant. */
  real e1[3], e2[3], pv[3], tv[3], qv[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    e1[i] = (real)tri->v1[i] - (real)tri->v0[i];
    e2[i] = (real)tri->v2[i] - (real)tri->v0[i];
    tv[i] = r->org[i] - (real)tri->v0[i];
  }
  pv[0] = r->dir[1] * e2[2] - r->dir[2] * e2[1];
  pv[1] = r->dir[2] * e2[0] - r->dir[0] * e2[2];
  pv[2] = r->dir[0] * e2[1] - r->dir[1] * e2[0];
  real det = Dot3(e1, pv);
  if (fabs(det) < (real)1e-9f) return 0;
  real invDet = (real)1.0f / det;
  real u = Dot3(tv, pv) * invDet;
  if (u < (real)0.0f || u > (real)1.0f) return 0;
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  real v = Dot3(r->dir, qv) * invDet;
  if (v < (real)0.0f || u + v > (real)1.0f) return 0;
  real t = Dot3(e2, qv) * invDet;
  if (t < tmin || t > tmax) return 0;
  *tHit = t;
  *uHit = u;
  *vHit = v;
  return 1;
#else
  /* Woop, Benthin & Wald 2013: translate to the ray origin, shear so the ray
   * is the +z axis, evaluate the 2D edge functions. An edge function that is
   * exactly 0 counts as inside for both neighbours, so no ray leaks through a
   * shared edge or vertex. */
  const int kx = r->kx, ky = r->ky, kz = r->kz;
  real A[3], B[3], C[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    A[i] = (real)tri->v0[i] - r->org[i];
    B[i] = (real)tri->v1[i] - r->org[i];
    C[i] = (real)tri->v2[i] - r->org[i];
  }
  const real Ax = CR_PICK3(A, kx) - r->sx * CR_PICK3(A, kz), Ay = CR_PICK3(A, ky) - r->sy * CR_PICK3(A, kz);
  const real Bx = CR_PICK3(B, kx) - r->sx * CR_PICK3(B, kz), By = CR_PICK3(B, ky) - r->sy * CR_PICK3(B, kz);
  const real Cx = CR_PICK3(C, kx) - r->sx * CR_PICK3(C, kz), Cy = CR_PICK3(C, ky) - r->sy * CR_PICK3(C, kz);
  real U = Cx * By - Cy * Bx;
  real V = Ax * Cy - Ay * Cx;
  real W = Bx * Ay - By * Ax;
#ifndef CR_FP64
  if (tri->flags & CR_TRI_LONG_EDGES) {
    const real nA = Triangle_Norm1(CR_PICK3(A, kx), CR_PICK3(A, ky), CR_PICK3(A, kz));
    const real nB = Triangle_Norm1(CR_PICK3(B, kx), CR_PICK3(B, ky), CR_PICK3(B, kz));
    const real nC = Triangle_Norm1(CR_PICK3(C, kx), CR_PICK3(C, ky), CR_PICK3(C, kz));
    if (Triangle_LongEdgeUndecided(tri->flags, nA, nB, nC, U, V, W)) Triangle_RefineEdges(r, tri, nA, nB, nC, &U, &V, &W);
  }
#endif
  if ((U < (real)0.0f || V < (real)0.0f || W < (real)0.0f) && (U > (real)0.0f || V > (real)0.0f || W > (real)0.0f))
    return 0;
  real det = U + V + W;
  if (det == (real)0.0f) return 0;
  /* The distance along the ray comes from the triangle's plane, not from
   * T / det: on a sliver det (twice the projected area) is small beside the
   * rounding of U, V, W, and T / det errs in proportion to the aspect ratio
   * (a hit on a 50 x 0.003 needle came out 1e-3 off its plane, at positive
   * t where the exact crossing was behind the origin: self-intersection).
   * The normal is the cross product of the shortest edge and the next one,
   * which meet at about a right angle on a needle, so it is accurate to a
   * few ulps; a zero-area triangle has n = 0 and is never hit. The inside
   * test above is unchanged, so the test stays watertight. */
  real n[3];
  const int shared = Triangle_PlaneNormal(tri, n);
  real p[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = shared == 1 ? B[i] : (shared == 2 ? C[i] : A[i]);
  const real nd = Dot3(n, r->dir);
  if (nd == (real)0.0f) return 0;
  const real np0 = n[0] * p[0], np1 = n[1] * p[1], np2 = n[2] * p[2];
  real t = ((np0 + np1) + np2) / nd;
#ifndef CR_FP64
  if (Triangle_PlaneInexact(np0, np1, np2)) {
    /* The origin near the triangle's plane relative to the shared vertex's
     * distance. A float hit whose three edge functions all lie within their
     * rounding then may be a small triangle seen edge-on from far away, its
     * projection degenerate (two can round to 0 and the third not: an
     * "inside" at the plane's crossing, far from the triangle): the three
     * edges again in double-float. Only then: a rule that fired on one edge
     * of a hit would decide that edge differently from the neighbour that
     * shares it (which missed, in float, on that edge) and could let a ray
     * through; with all three edges below their rounding the hit is
     * marginal anyway, and no ray from inside a mesh sees one. Away from
     * the plane the crossing lies within a few ulps of the distance of the
     * triangle, and the float answer stands (docs/TOLERANCE.md). */
    if (Triangle_EdgesUndecided(Triangle_Norm1(CR_PICK3(A, kx), CR_PICK3(A, ky), CR_PICK3(A, kz)),
                                Triangle_Norm1(CR_PICK3(B, kx), CR_PICK3(B, ky), CR_PICK3(B, kz)),
                                Triangle_Norm1(CR_PICK3(C, kx), CR_PICK3(C, ky), CR_PICK3(C, kz)), U, V, W)) {
      Triangle_EdgesDf(r, tri, &U, &V, &W);
      if ((U < (real)0.0f || V < (real)0.0f || W < (real)0.0f) &&
          (U > (real)0.0f || V > (real)0.0f || W > (real)0.0f))
        return 0;
      det = U + V + W;
      if (det == (real)0.0f) return 0;
    }
    if (Triangle_PlaneNeedsDf(np0, np1, np2, nd, t, tmin, tmax)) t = Triangle_PlaneTDf(r->org, r->dir, tri);
  }
#endif
  if (!(t >= tmin && t <= tmax)) return 0;
  const real invDet = (real)1.0f / det;
  *tHit = t;
  *uHit = V * invDet;
  *vHit = W * invDet;
  return 1;
#endif
}

/* Open cone or cylinder (NFF `c`): the quadric |radial|^2 = r(s)^2 with
 * r(s) = r0 + (r1 - r0) s / H, kept for axial s in [0, H]. */
CR_FUNC int Cone_Intersect(const Ray* r, const Cone* cn, real tmin, real tmax, real* tHit)
{
  real w[3], dl[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    w[i] = (real)cn->apex[i] - (real)cn->base[i];
    dl[i] = r->org[i] - (real)cn->base[i];
  }
  const real H = sqrt(Dot3(w, w));
  if (!(H > (real)0.0f)) return 0;
  CR_UNROLL for (int i = 0; i < 3; ++i) w[i] = w[i] / H;
  const real r0 = (real)cn->baseRadius;
  const real k = ((real)cn->apexRadius - r0) / H;
  const real ds = Dot3(r->dir, w);
  const real os = Dot3(dl, w);
  real dR[3], oR[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    dR[i] = r->dir[i] - ds * w[i];
    oR[i] = dl[i] - os * w[i];
  }
  const real rb = r0 + k * os;
  const real A = Dot3(dR, dR) - k * k * ds * ds;
  const real Bh = Dot3(oR, dR) - k * ds * rb;
  const real C = Dot3(oR, oR) - rb * rb;
  real t0, t1;
  if (A == (real)0.0f) {
    if (Bh == (real)0.0f) return 0;
    t0 = t1 = -C / ((real)2.0f * Bh);
  } else {
#ifdef CR_FAST
    real disc4 = (real)4.0f * Bh * Bh - (real)4.0f * A * C;
    if (disc4 < (real)0.0f) return 0;
    real sq = sqrt(disc4);
    real ta = (-(real)2.0f * Bh - sq) / ((real)2.0f * A);
    real tb = (-(real)2.0f * Bh + sq) / ((real)2.0f * A);
    t0 = fmin(ta, tb);
    t1 = fmax(ta, tb);
#else
    /* Bh^2 - A C = |rb dR - k ds oR|^2 - |oR x dR|^2 (expand both sides):
     * the same cure as for spheres, no cancellation between two large
     * squares when the cone is thin and far away. */
    real e[3], x[3];
    CR_UNROLL for (int i = 0; i < 3; ++i) e[i] = rb * dR[i] - k * ds * oR[i];
    x[0] = oR[1] * dR[2] - oR[2] * dR[1];
    x[1] = oR[2] * dR[0] - oR[0] * dR[2];
    x[2] = oR[0] * dR[1] - oR[1] * dR[0];
    const real ee = Dot3(e, e), xx = Dot3(x, x);
    real disc = ee - xx;
#ifndef CR_FP64
    /* A discriminant within its rounding of 0 (a ray grazing a huge cone):
     * hit or miss decided in double-float. */
    if (disc < (real)0.0f && -disc <= 0x1.0p-20f * (ee + xx))
      return Cone_IntersectDf(r->org, r->dir, cn, tmin, tmax, tHit);
#endif
    if (disc < (real)0.0f) return 0;
    const real oo = Dot3(oR, oR);
    real q;
    Quadratic_Roots(A, Bh, C, oo + rb * rb, disc, &t0, &t1, &q);
#ifndef CR_FP64
    if (Cone_NeedsDf(C, oo + rb * rb, Bh, disc, ee, xx, q, Dot3(dl, dl), oo, k, ds, rb, Dot3(dR, dR),
                     Dot3(r->dir, r->dir), A, t0, t1, tmin, tmax))
      return Cone_IntersectDf(r->org, r->dir, cn, tmin, tmax, tHit);
#endif
#endif
  }
  if (t0 >= tmin && t0 <= tmax) {
    real s = os + t0 * ds;
    if (s >= (real)0.0f && s <= H) {
      *tHit = t0;
      return 1;
    }
  }
  if (t1 >= tmin && t1 <= tmax) {
    real s = os + t1 * ds;
    if (s >= (real)0.0f && s <= H) {
      *tHit = t1;
      return 1;
    }
  }
  return 0;
}

/* Tests primitive g and keeps the hit if it is closer (Hit_Closer). Returns 1
 * when the hit changed. */
CR_FUNC_HOT int Prim_Intersect(const PrimView* pv, uint g, const Ray* r, Hit* hit)
{
  real t = (real)0.0f, u = (real)0.0f, v = (real)0.0f;
  int found = 0;
#if CR_HAS_SPHERES
  /* In type order: each test below knows g is past the types above. */
  if (g < Prim_End(&pv->ranges, CR_PRIM_SPHERE)) {
    const Sphere s = pv->spheres[Prim_Local(&pv->ranges, CR_PRIM_SPHERE, g)];
    found = Sphere_Intersect(r, &s, r->tmin, hit->t, &t);
  } else
#endif
#if CR_HAS_TRIANGLES
      if (g < Prim_End(&pv->ranges, CR_PRIM_TRIANGLE)) {
    const Triangle tri = pv->triangles[Prim_Local(&pv->ranges, CR_PRIM_TRIANGLE, g)];
    found = Triangle_Intersect(r, &tri, r->tmin, hit->t, &t, &u, &v);
  } else
#endif
  {
#if CR_HAS_CONES
    const Cone cn = pv->cones[Prim_Local(&pv->ranges, CR_PRIM_CONE, g)];
    found = Cone_Intersect(r, &cn, r->tmin, hit->t, &t);
#endif
  }
  if (found && Hit_CloserOn(pv, r, t, g, hit)) {
    hit->t = t;
    hit->u = u;
    hit->v = v;
    hit->g = g;
    return 1;
  }
  return 0;
}

/* How far boxes and cells are still entered for a closest hit at t: a little
 * beyond t. A primitive lying in a face of its box (coplanar faces of a mesh)
 * can have a computed t a few ulps below the box's computed entry; culling
 * that box at exactly t would make the nearest answer depend on which box was
 * visited first, and so differ between traversal orders and backends.
 * 8 ulps (2^-20 relative) covers it; fast mode culls at t. */
CR_FUNC real Cull_Distance(real t)
{
#ifdef CR_FAST
  return t;
#elif defined(CR_FP64)
  return t * ((real)1.0f + (real)0x1.0p-49f);
#else
  return t * (1.0f + 0x1.0p-20f);
#endif
}

/* Conservative slab test of a box against [tmin, tmax] (Williams et al. 2005
 * with Ize 2013's rounding: the far distance is scaled by 1 + 2 gamma(3) so
 * that rounding can never cull a box the exact ray enters). 0 * inf = NaN on
 * a plane-parallel ray is dropped by fmin/fmax. The corners come as private
 * values, so that boxes in any address space share it. Writes the entry
 * distance. */
CR_FUNC int Box_Slabs(const real lo3[3], const real hi3[3], const Ray* r, real tmin, real tmax, real* tEnter)
{
  real tn = tmin, tf = tmax;
  real boxFar = (real)CR_INF;
  real boxNear = -(real)CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    real lo = (lo3[a] - r->org[a]) * r->inv[a];
    real hi = (hi3[a] - r->org[a]) * r->inv[a];
    real n = r->inv[a] < (real)0.0f ? hi : lo;
    real f = r->inv[a] < (real)0.0f ? lo : hi;
    boxNear = fmax(boxNear, n);
    boxFar = fmin(boxFar, f);
  }
#ifndef CR_FAST
#ifdef CR_FP64
  boxFar = boxFar * (real)1.0000000000000007;
#else
  boxFar = boxFar * 1.0000004f;
#endif
#endif
  tn = fmax(tn, boxNear);
  tf = fmin(tf, boxFar);
  *tEnter = tn;
  return tn <= tf;
}

/* Box_Slabs of a box in global memory. */
CR_FUNC int Box_Intersect(CR_GLOBAL const float* bmin, CR_GLOBAL const float* bmax, const Ray* r, real tmin, real tmax,
                          real* tEnter)
{
  real lo[3], hi[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    lo[a] = (real)bmin[a];
    hi[a] = (real)bmax[a];
  }
  return Box_Slabs(lo, hi, r, tmin, tmax, tEnter);
}

/* The .hits record of a finished query: closest hit (t, prim id, u, v) or
 * occlusion (t = 0, an occluder's id); a miss is (+inf, CR_NO_HIT). u, v are
 * reported for whole triangle statements only (FORMATS.md).
 * With `unified` set, the record is the renderer's internal form instead: prim
 * holds the unified piece index g and u, v are the barycentrics of every
 * triangle piece (primIds is not read). */
CR_FUNC HitRecord Hit_ToRecord(const Hit* h, const PrimView* pv, CR_GLOBAL const uint* primIds, int anyHit, int unified)
{
  HitRecord r;
  r.u = 0.0f;
  r.v = 0.0f;
  if (h->g == CR_NO_HIT) {
    r.t = CR_INF;
    r.prim = CR_NO_HIT;
    return r;
  }
  r.prim = unified ? h->g : primIds[h->g];
  r.t = anyHit ? 0.0f : (float)h->t;
  if (!anyHit && Prim_Is(&pv->ranges, CR_PRIM_TRIANGLE, h->g) &&
      (unified || (pv->triangles[Prim_Local(&pv->ranges, CR_PRIM_TRIANGLE, h->g)].flags & CR_TRI_REPORT_UV))) {
    r.u = (float)h->u;
    r.v = (float)h->v;
  }
  return r;
}

#endif /* CELLRAY_KERNELS_INTERSECT_H */
