/* Numerics shared by the primitive tests (each type's kernels/<type>.h):
 * the stable quadratic, and in robust mode the error-free
 * transformations and double-float arithmetic of their cold paths. */
#ifndef CELLRAY_KERNELS_NUMERIC_H
#define CELLRAY_KERNELS_NUMERIC_H
#include "ray.h"

/* Error-free transformations in `real` (float, or double in fp64 mode):
 * a + b = s + e and a b = p + e exactly (Knuth's TwoSum; Dekker's
 * TwoProduct with Veltkamp's split, no FMA, so every device gets the same
 * bits). Robust mode's double-float arithmetic below is built on them. */
CR_FUNC real Rt_TwoSum(real a, real b, real* e)
{
  const real s = a + b;
  const real bb = s - a;
  *e = (a - (s - bb)) + (b - bb);
  return s;
}
CR_FUNC real Rt_TwoProduct(real a, real b, real* e)
{
#ifdef CR_FP64
  const real split = 134217729.0; /* 2^27 + 1 */
#else
  const real split = 4097.0f; /* 2^12 + 1 */
#endif
  const real p = a * b;
  const real ca = split * a, cb = split * b;
  const real ah = ca - (ca - a), bh = cb - (cb - b);
  const real al = a - ah, bl = b - bh;
  *e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
  return p;
}
#if !defined(CR_FAST) && !defined(CR_FP64)
/* a b - c d to a few ulps even when the two products cancel. */
CR_FUNC float Ef_DiffOfProducts(float a, float b, float c, float d)
{
  float e1, e2, es;
  const float p1 = Rt_TwoProduct(a, b, &e1);
  const float p2 = Rt_TwoProduct(c, d, &e2);
  const float s = Rt_TwoSum(p1, -p2, &es);
  return s + (es + (e1 - e2));
}

/* |a| >= |b| (or a == 0): a + b = s + e exactly. */
CR_FUNC float Ef_FastTwoSum(float a, float b, float* e)
{
  const float s = a + b;
  *e = b - (s - a);
  return s;
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
  r.hi = Rt_TwoSum(a, b, &r.lo);
  return r;
}
CR_FUNC Df Df_ProdF(float a, float b)
{
  Df r;
  r.hi = Rt_TwoProduct(a, b, &r.lo);
  return r;
}
CR_FUNC Df Df_Add(Df a, Df b)
{
  float e;
  const float s = Rt_TwoSum(a.hi, b.hi, &e);
  return Df_Norm(s, e + (a.lo + b.lo));
}
CR_FUNC Df Df_Sub(Df a, Df b) { return Df_Add(a, Df_Neg(b)); }
CR_FUNC Df Df_Mul(Df a, Df b)
{
  float e;
  const float p = Rt_TwoProduct(a.hi, b.hi, &e);
  return Df_Norm(p, e + (a.hi * b.lo + a.lo * b.hi));
}
CR_FUNC Df Df_MulF(Df a, float b)
{
  float e;
  const float p = Rt_TwoProduct(a.hi, b, &e);
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
  const float p = Rt_TwoProduct(s, s, &e);
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
/* Roots of a t^2 + 2 bh t + c = 0 in double-float given disc >= 0, in
 * double-float, unordered: q / a and c / q with q = -(bh + sign(bh) sqrt(disc))
 * (c / q is q / a again where q = 0). */
CR_FUNC void Df_QuadraticRootsDf(Df a, Df bh, Df c, Df disc, Df* r0, Df* r1)
{
  Df sq = Df_Sqrt(disc);
  if (bh.hi < 0.0f) sq = Df_Neg(sq);
  const Df q = Df_Neg(Df_Add(bh, sq));
  *r0 = Df_Div(q, a);
  *r1 = q.hi != 0.0f ? Df_Div(c, q) : *r0;
}
/* The same roots as float (the nearest float to hi + lo is hi), smaller
 * first. */
CR_FUNC void Df_QuadraticRoots(Df a, Df bh, Df c, Df disc, real* t0, real* t1)
{
  Df r0, r1;
  Df_QuadraticRootsDf(a, bh, c, disc, &r0, &r1);
  *t0 = fmin(r0.hi, r1.hi);
  *t1 = fmax(r0.hi, r1.hi);
}
#endif

/* The sum of p[0..n) (n >= 1) to about one rounding of itself plus
 * (n u)^4 of the sum of the terms' magnitudes: Ogita, Rump & Oishi's SumK
 * ("Accurate sum and dot product", SIAM J. Sci. Comput. 2005) with K = 4:
 * three cascades of TwoSum that each leave the sum in p[n-1] and the exact
 * errors below it, then the plain sum. For terms that cancel by many orders
 * of magnitude (|o - c|^2 - r^2 of a ground sphere seen from just above
 * it). Overwrites p. */
CR_FUNC real Rt_SumK4(real* p, int n)
{
  for (int pass = 0; pass < 3; ++pass)
    for (int i = 1; i < n; ++i) p[i] = Rt_TwoSum(p[i], p[i - 1], &p[i - 1]);
  real s = (real)0.0f;
  for (int i = 0; i + 1 < n; ++i) s += p[i];
  return s + p[n - 1];
}

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

#endif /* CELLRAY_KERNELS_NUMERIC_H */
