/* The sphere (NFF `s`): its robust cold paths (the discriminant and the
 * roots in double-float, the order of exact float ties) and its test. The
 * layout is Sphere of kernels/types.h. */
#ifndef CELLRAY_KERNELS_SPHERE_H
#define CELLRAY_KERNELS_SPHERE_H
#include "numeric.h"

#ifndef CR_HAS_SPHERE
#define CR_HAS_SPHERE 1
#endif

/* c = |o - centre|^2 - r^2 in `real`, accurately: f = o - centre as exact
 * pairs (TwoSum), its squares and cross terms and r^2 as exact products
 * (TwoProduct), summed by Rt_SumK4, so that the squares that cancel (a
 * ground sphere of radius 1e6 seen from 6e-7 above it: |f|^2 and r^2 are
 * 1e12, c is 1.18) cancel exactly before the small terms are added. Robust
 * mode's double-float c (48 bits of |f|^2) erred by 3e-4 there, fp64 mode's
 * double (f rounded) by 2e-4: roots 2e-8 off, twice the checker's
 * tolerance. The cold path of both modes (2^20 diffuse rays of
 * scenes/scale/mixed-scales.nff found it). Inline: in fp64 mode's sphere
 * test it costs 14 VGPRs on gfx906 (111 -> 125 in the grid kernels with
 * spheres, still 2 waves); as a call (CR_COLD) a 160-byte frame in scratch,
 * which the GPU compile table's goal rules out. */
CR_FUNC real Sphere_CAccurate(const real org[3], const Sphere* s)
{
  real p[17];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    real fl;
    const real fh = Rt_TwoSum(org[i], -(real)s->center[i], &fl);
    p[5 * i] = Rt_TwoProduct(fh, fh, &p[5 * i + 1]);
    p[5 * i + 2] = Rt_TwoProduct((real)2.0f * fh, fl, &p[5 * i + 3]);
    p[5 * i + 4] = fl * fl;
  }
  p[15] = -Rt_TwoProduct((real)s->radius, (real)s->radius, &p[16]);
  p[16] = -p[16];
  return Rt_SumK4(p, 17);
}

#if !defined(CR_FAST) && !defined(CR_FP64)
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
    fh[i] = Rt_TwoSum(org[i], -s->center[i], &fl[i]);
    real e, se;
    real p = Rt_TwoProduct(fh[i], dir[i], &e);
    bhH = Rt_TwoSum(bhH, p, &se);
    bhL = bhL + (se + (e + fl[i] * dir[i]));
    p = Rt_TwoProduct(dir[i], dir[i], &e);
    aH = Rt_TwoSum(aH, p, &se);
    aL = aL + (se + e);
  }
  bhH = Ef_FastTwoSum(bhH, bhL, &bhL);
  aH = Ef_FastTwoSum(aH, aL, &aL);
  const real disc = Sphere_DiscOfExactF(fh, fl, dir, aH * s->radius * s->radius);
  const real sq = disc > 0.0f ? CR_SQRTF(disc) : 0.0f;
  real nL, qL, pe;
  for (int root = 0; root < 2; ++root) {
    /* numerator -bh -+ sq, then the quotient by a */
    real nH = Rt_TwoSum(-bhH, root == 0 ? -sq : sq, &nL);
    nL = nL - bhL;
    nH = Ef_FastTwoSum(nH, nL, &nL);
    const real qH = nH / aH;
    const real p = Rt_TwoProduct(qH, aH, &pe);
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
 * - the root q / a is within rel of itself; c / q too, plus c's error over
 *   |q|: e, 16u cScale (c = |f|^2 - r^2 errs by at most about 6u cScale:
 *   f = o - c by u |f|, the sum of squares by 3u; a random search found
 *   2.6u); where Quadratic_Roots takes (sq - bh) / a instead
 *   (16 q^2 < a cScale) that root carries eq / a, rel of the other root, so
 *   both windows take the larger root's share (m).
 * First order holds: disc's error is below a quarter of disc wherever this
 * is reached (Sphere_DiscUndecided and the 2^36 rule took the rest). */
CR_FUNC int Sphere_NeedsDf(real c, real cScale, real bh, real disc, real dScale, real q, real a, real ff, real cc,
                           real t0, real t1, real tmin, real tmax, int anyHit)
{
  const real dd = disc * (bh * bh + disc);
  const real ds2 = dScale * dScale;
  if (!(cScale > 8.0f * fabs(c) || ds2 > 64.0f * dd)) return 0;
  if (ds2 > 0x1.0p36f * dd || !(disc > (real)0.0f)) return 1;
  const real af = a * ff;
  const real eq = 0x1.0p-20f * ((sqrt(af * cc) + dScale) / sqrt(disc) + sqrt(af));
  const real rel = eq / fabs(q) + 0x1.0p-20f;
  const real e = 0x1.0p-20f * cScale / fabs(q);
  const real m = (real)16.0f * q * q >= a * cScale ? (real)0.0f : fmax(fabs(t0), fabs(t1));
  const real s0 = rel * fmax(fabs(t0), m) + e, s1 = rel * fmax(fabs(t1), m) + e;
  /* An any-hit query needs no exact t: a root whose whole window lies in
   * range is a hit for certain (a shadow ray from the ground next to a ball
   * that hides the light). */
  if (anyHit && ((t0 - s0 > tmin && t0 + s0 < tmax) || (t1 - s1 > tmin && t1 + s1 < tmax))) return 0;
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
  const Df c = Df_F(Sphere_CAccurate(org, s));
  /* An origin outside the sphere moving away from it (c > 0, bh > 0: a ray
   * leaving the surface, the commonest reason to be here) has both roots
   * negative: q = -(bh + sq) < 0, q / a < 0 and c / q < 0, each at least
   * 2^-101 from 0 by the margins below (no quotient underflows to -0). */
  if (tmin >= 0.0f && bh.hi > 0x1.0p-100f * a.hi && c.hi > 0x1.0p-100f * bh.hi) return 0;
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

/* Sphere_IntersectDf for a ray whose float discriminant is undecided
 * (Sphere_DiscUndecided): most such rays pass the sphere by more than the
 * error of the discriminant recomputed from the exact o - c and exact
 * products (Sphere_DiscOfExactF), and are certain misses without the
 * double-float test. That error, to first order (u = 2^-24): ar2 = a r^2 in
 * float by 5u; each cross-product component by 2u |cx| + 5u^2 |f| |d| (the
 * exact products' sum and the fl terms, each rounded); their squares' sum
 * by 7u cc; so below 8u (ar2 + cc) + 9u^2 (cc + |f|^2 |d|^2) (the cross
 * term, with 2 xy <= x^2 + y^2). Taken as 2^-20 (ar2 + cc) + 2^-13 Q
 * (Q = 2^-29 |f|^2 |d|^2: 64u^2 against 9u^2), with cc from the
 * recomputed disc. NaN and overflow fall through to double-float. */
CR_COLD CR_FUNC int Sphere_IntersectUndecided(const real org[3], const real dir[3], const Sphere* s, real tmin,
                                              real tmax, real ar2, real Q, real* tHit)
{
  real fh[3], fl[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) fh[i] = Rt_TwoSum(org[i], -s->center[i], &fl[i]);
  const real de = Sphere_DiscOfExactF(fh, fl, dir, ar2);
  if (de < -(0x1.0p-20f * (ar2 + (ar2 - de)) + 0x1.0p-13f * Q)) return 0;
  return Sphere_IntersectDf(org, dir, s, tmin, tmax, tHit);
}

#endif

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
  real cScale = ff + rad * rad; /* c's error is about u cScale */
#ifdef CR_FP64
  /* c lost more than 26 of double's 53 bits to cancellation (an origin on
   * or near a huge sphere): the accurate sum, from the exact o - centre,
   * whose error is about u |c| (so Quadratic_Roots takes c / q). */
  if (fabs(c) < 0x1.0p-26 * cScale) {
    c = Sphere_CAccurate(r->org, s);
    cScale = fabs(c);
  }
#endif
  real t0, t1;
#ifdef CR_FAST
  (void)cScale;
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
  if (Sphere_DiscUndecided(disc, Q, cc)) return Sphere_IntersectUndecided(r->org, r->dir, s, tmin, tmax, ar2, Q, tHit);
#endif
  if (disc < (real)0.0f) return 0;
  real q;
  Quadratic_Roots(a, bh, c, cScale, disc, &t0, &t1, &q);
#ifndef CR_FP64
  if (Sphere_NeedsDf(c, ff + rad * rad, bh, disc, ar2 + cc, q, a, ff, cc, t0, t1, tmin, tmax, r->anyHit))
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

/* The uniform form of the dispatch (CR_PRIM_TYPES): no barycentrics. */
CR_FUNC int Sphere_Test(const Ray* r, const Sphere* s, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
  return Sphere_Intersect(r, s, tmin, tmax, tHit);
}
/* A copy of a sphere in global memory (field by field, as the packet
 * kernels' vectorisers prefer). */
CR_FUNC Sphere Sphere_Load(CR_GLOBAL const Sphere* p)
{
  Sphere s;
  CR_UNROLL for (int a = 0; a < 3; ++a) s.center[a] = p->center[a];
  s.radius = p->radius;
  return s;
}

#endif /* CELLRAY_KERNELS_SPHERE_H */
