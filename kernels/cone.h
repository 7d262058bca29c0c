/* The open cone or cylinder (NFF `c`): its robust cold paths (the roots in
 * double-float) and its test. The layout is Cone of kernels/types.h. */
#ifndef CELLRAY_KERNELS_CONE_H
#define CELLRAY_KERNELS_CONE_H
#include "numeric.h"

#ifndef CR_HAS_CONE
#define CR_HAS_CONE 1
#endif

#if !defined(CR_FAST) && !defined(CR_FP64)
/* Sphere_NeedsDf's rule for a cone (Cone_Intersect), or o - base much longer than its radial part
 * oR (a long cone seen from beside its middle: oR carries the rounding of
 * o - base, relatively |dl| / |oR| ulps; always redone past 2^18). Then C's
 * error grows with |dl| too. To first order (u = 2^-24): oR's radial part
 * within 4u |dl| + u |oR| (o - base, the axis's direction and the products
 * each round by about u |dl|), os within 9u |dl|, k within 5u |k|, so C
 * within 8u |oR| |dl| + 28u |k rb| |dl| + 6u cScale; e bounds it by 16u
 * |oR| |dl| + 64u |k rb| |dl| + 16u cScale (a random search over long,
 * thin, huge and tilted cones with origins on and near their surfaces found
 * at most 0.6 of the first bound). Each root gets its
 * own window, rel of itself plus e / |q|, rel bounding q's and A's relative
 * errors (below; always redone past 1/16): a ray leaving the cone's surface
 * is redone only when its near root may lie in range, not because the far
 * root is large. Where the other root is (sq - bh) / A, it carries q's error
 * divided by A: both windows then take the larger root's share, as for
 * Sphere_NeedsDf. */
CR_FUNC int Cone_NeedsDf(real C, real cScale, real Bh, real disc, real ee, real xx, real q, real dl2, real oo, real k,
                         real ds, real rb, real dd, real A, real t0, real t1, real tmin, real tmax, real os,
                         real H, int anyHit)
{
  const real dScale = ee + xx;
  const real d2 = disc * (Bh * Bh + disc);
  if (!(cScale > 8.0f * fabs(C) || dScale * dScale > 64.0f * d2 || dl2 > 64.0f * oo)) return 0;
  if (dScale * dScale > 0x1.0p36f * d2 || dl2 > 0x1.0p36f * oo || !(disc > (real)0.0f)) return 1;
  const real ndl = sqrt(dl2), nd = sqrt(dd), noR = sqrt(oo), kds = fabs(k * ds), ak = fabs(k), arb = fabs(rb);
  /* First-order bounds (u = 2^-24, generously): oR within 11u |dl|, dR
   * within 6u |d|, rb within 4u |k| |dl| + 2u |rb|; so e = rb dR - k ds oR
   * within Ee, x = oR x dR within Ex, disc = ee - xx within eDisc, Bh within
   * eB, A within eA; q within eq, its root's share relative to |q|. Cheaply:
   * |dR| <= |d|, and sqrt(ee), sqrt(xx) <= sqrt(ee + xx). */
  const real Ee = 0x1.0p-20f * ((ak * ndl + 2.0f * arb) * nd + kds * ndl);
  const real Ex = 0x1.0p-19f * ((ndl + noR) * nd);
  const real eDisc = 2.0f * sqrt(dScale) * (Ee + Ex) + 0x1.0p-21f * dScale;
  const real eB = 0x1.0p-20f * (ndl * (nd + ak * kds) + noR * nd + kds * arb);
  const real eA = 0x1.0p-19f * (dd + kds * (kds + ak * nd));
  const real iq = 1.0f / fabs(q);
  const real rel = (eDisc / (2.0f * sqrt(disc)) + eB) * iq + eA / fabs(A) + 0x1.0p-20f;
  if (!(eDisc < 0.25f * disc && rel < 0.0625f)) return 1;
  const real e = 0x1.0p-20f * (cScale + ndl * (noR + 4.0f * fabs(k * rb))) * iq;
  const real m = (real)16.0f * q * q >= A * cScale ? (real)0.0f : fmax(fabs(t0), fabs(t1));
  const real s0 = rel * fmax(fabs(t0), m) + e, s1 = rel * fmax(fabs(t1), m) + e;
  /* A root whose axial position is certainly outside [0, H] is a miss
   * however far off t is (a ray leaving a branch near the joint crosses the
   * neighbouring cone's infinite surface there, before its base). The float
   * os + t ds is within 2^-20 (|dl| + |t| |d| + H) + |ds| s of the exact
   * position at the exact root (os carries about 9u |dl|, ds 8u |d|, H 3u). */
  const real a0 = os + t0 * ds, a1 = os + t1 * ds;
  const real ea0 = 0x1.0p-20f * (ndl + fabs(t0) * nd + H) + fabs(ds) * s0;
  const real ea1 = 0x1.0p-20f * (ndl + fabs(t1) * nd + H) + fabs(ds) * s1;
  /* Any-hit: a root in range for certain, at an axial position inside
   * [0, H] for certain, is a hit whatever its exact t (Sphere_NeedsDf). */
  if (anyHit && ((t0 - s0 > tmin && t0 + s0 < tmax && a0 - ea0 > (real)0.0f && a0 + ea0 < H) ||
                 (t1 - s1 > tmin && t1 + s1 < tmax && a1 - ea1 > (real)0.0f && a1 + ea1 < H)))
    return 0;
  return (t0 + s0 >= tmin && t0 - s0 <= tmax && a0 + ea0 >= (real)0.0f && a0 - ea0 <= H) ||
         (t1 + s1 >= tmin && t1 - s1 <= tmax && a1 + ea1 >= (real)0.0f && a1 - ea1 <= H);
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
    if (Cone_NeedsDf(C, oo + rb * rb, Bh, disc, ee, xx, q, Dot3(dl, dl), oo, k, ds, rb,
                     Dot3(r->dir, r->dir), A, t0, t1, tmin, tmax, os, H, r->anyHit))
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
/* The uniform form of the dispatch (CR_PRIM_TYPES): no barycentrics. */
CR_FUNC int Cone_Test(const Ray* r, const Cone* cn, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
  return Cone_Intersect(r, cn, tmin, tmax, tHit);
}
/* A copy of a cone in global memory (field by field). */
CR_FUNC Cone Cone_Load(CR_GLOBAL const Cone* p)
{
  Cone c;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    c.base[a] = p->base[a];
    c.apex[a] = p->apex[a];
  }
  c.baseRadius = p->baseRadius;
  c.apexRadius = p->apexRadius;
  return c;
}

#endif /* CELLRAY_KERNELS_CONE_H */
