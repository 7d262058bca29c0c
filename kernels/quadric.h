/* The quadric surface clipped to a box (NFF extension `quadric A B C D E F G
 * H I J xmin ymin zmin xmax ymax zmax`, docs/FORMATS.md): ellipsoids,
 * paraboloids, hyperboloids, cylinders, cones, pairs of planes. The layout is
 * Quadric of kernels/types.h: the surface
 *     f(x) = x^T Q x + 2 l . x + j = 0,   x = p - centre,
 * in coordinates relative to the clip box's centre (the host re-expresses
 * the statement's coefficients there, in double, before rounding them), and
 * the clip box |x[i]| <= extent[i]. Centring keeps the numbers of a small
 * quadric far from the world origin at its own scale.
 *
 * Along the ray x = x0 + t d (x0 = o - centre): a t^2 + 2 bh t + c = 0 with
 *     a = d . Q d,   bh = d . (Q x0 + l),   c = x0 . (Q x0 + 2 l) + j;
 * roots q / a and c / q with q = -(bh + sign(bh) sqrt(bh^2 - a c)) (no
 * cancellation between -bh and the root; a = 0, a ray along a paraboloid's
 * axis or a cylinder's, leaves the one root c / q). The hit is the first
 * root in [tmin, tmax] whose point lies in the clip box: a ray that enters
 * an open cylinder through its rim sees the inside wall, the second root.
 *
 * Robust mode: each of a, bh, c is computed with its scale (the same sum of
 * absolute values: aS, bS, cS), float's error bounds follow from them, and
 * where a root that may lie in [tmin, tmax] may be off by more than 2^-17 of
 * the checker's tolerance scale |o|/|d| + |t| (the checker allows 2^-16 of
 * |o|inf + t |d|inf in world units, at least 2^-16 / sqrt(3) of that scale
 * in t: the worst-case first-order bound stays within 0.87 of it; the real
 * errors are far smaller, docs/TOLERANCE.md), or where the
 * discriminant is within four times its own error of
 * 0 (hit or miss undecided), the whole test runs again in double-float from
 * the exact o - centre (Quadric_IntersectDf); so does a root whose point
 * lies within its error of a face of the clip box (Quadric_BoxUndecided),
 * where the double-float test decides with the root in double-float. That
 * covers the quadric's
 * versions of the sphere's cases: a ground ellipsoid 1e6 across seen from
 * 10 above (c cancels), a tiny quadric far away (the discriminant cancels),
 * a ray leaving the surface (c near 0, its root near 0).
 *
 * Error bounds, first order (u = 2^-24; x0 = o - centre is rounded once,
 * relative u): Q x0 + l per component within 5u of its scale (3 products, 3
 * sums, x0's own rounding), so bh within 8u bS (3 more products and sums)
 * and c within 11u cS; a within 6u aS. We take 8u for a, 10u for bh and 12u
 * for c (a first version took 16u, 16u and 32u, the root's error as
 * ed / sqrt(disc), against an eighth of the tolerance, and sent 20-35% of
 * the tests of a plain scene to double-float, 4x slower); the discriminant
 * bh^2 - a c within ed = 2|bh| eb + |a| ec + |c| ea + 3u (bh^2 + |a c|); its
 * root within ed / (sqrt(disc) + sqrt(disc - ed)) <= 0.54 ed / sqrt(disc)
 * (disc > 4 ed here; we take 0.5625); q within eb +
 * e_sq + u|q|; the roots within |t| (eq/|q| + ea/|a| + u) (q / a) and
 * ec/|q| + |t| (eq/|q| + u) (c / q). */
#ifndef CELLRAY_KERNELS_QUADRIC_H
#define CELLRAY_KERNELS_QUADRIC_H
#include "numeric.h"

#ifndef CR_HAS_QUADRIC
#define CR_HAS_QUADRIC 1
#endif

/* Q v for the symmetric Q with entries q: xx, yy, zz, xy, xz, yz. */
CR_FUNC void Quadric_MulQ(const float q[6], const real v[3], real out[3])
{
  out[0] = (real)q[0] * v[0] + (real)q[3] * v[1] + (real)q[4] * v[2];
  out[1] = (real)q[3] * v[0] + (real)q[1] * v[1] + (real)q[5] * v[2];
  out[2] = (real)q[4] * v[0] + (real)q[5] * v[1] + (real)q[2] * v[2];
}

/* Is x0 + t d in the clip box? */
CR_FUNC int Quadric_InBox(const Quadric* s, const real x0[3], const real d[3], real t)
{
  int in = 1;
  CR_UNROLL for (int i = 0; i < 3; ++i) in = in && fabs(x0[i] + t * d[i]) <= (real)s->extent[i];
  return in;
}

/* The first of the roots t0 <= t1 in [tmin, tmax] whose point is in the box. */
CR_FUNC int Quadric_Pick(const Quadric* s, const real x0[3], const real d[3], real t0, real t1, real tmin,
                         real tmax, real* tHit)
{
  if (t0 >= tmin && t0 <= tmax && Quadric_InBox(s, x0, d, t0)) {
    *tHit = t0;
    return 1;
  }
  if (t1 >= tmin && t1 <= tmax && Quadric_InBox(s, x0, d, t1)) {
    *tHit = t1;
    return 1;
  }
  return 0;
}

#if !defined(CR_FAST) && !defined(CR_FP64)
/* Is x0 + t d in the clip box, with t within e of the root and x0 rounded
 * once? 1 for certain, 0 certainly not, -1 undecided: the point lies within
 * its error of a face (e |d| for the root, 4u (|x0| + |t d|) for x0's
 * rounding, the product and the sum). A surface that meets a face at a
 * grazing angle (a parabolic cylinder whose vertex line lies in a face) puts
 * hits there that float rounding moves out of the box. */
CR_FUNC int Quadric_InBoxRobust(const Quadric* s, const real x0[3], const real d[3], real t, real e)
{
  int undecided = 0;
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    const real td = t * d[i];
    const real p = fabs(x0[i] + td);
    const real ep = e * fabs(d[i]) + 0x1.0p-22f * (fabs(x0[i]) + fabs(td));
    if (p - ep > (real)s->extent[i]) return 0;
    undecided = undecided || p + ep >= (real)s->extent[i];
  }
  return undecided ? -1 : 1;
}

/* Whether Quadric_Pick's choice between the roots lo <= hi (each within e)
 * rests on an undecided box test: the first root in [tmin, tmax] whose box
 * test is not certainly "out" is undecided. */
CR_FUNC int Quadric_BoxUndecided(const Quadric* s, const real x0[3], const real d[3], real lo, real hi, real e,
                                 real tmin, real tmax)
{
  const int b0 = lo >= tmin && lo <= tmax ? Quadric_InBoxRobust(s, x0, d, lo, e) : 0;
  if (b0 != 0) return b0 < 0;
  return hi >= tmin && hi <= tmax && Quadric_InBoxRobust(s, x0, d, hi, e) < 0;
}

/* Is the point x + t d in the clip box? In double-float: x exact (o -
 * centre), t a double-float root. */
CR_FUNC int Quadric_InBoxDf(const Quadric* s, const Df x[3], const real d[3], Df t)
{
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    Df p = Df_Add(x[i], Df_MulF(t, d[i]));
    if (p.hi < 0.0f) p = Df_Neg(p);
    if (!(Df_Sub(p, Df_F(s->extent[i])).hi <= 0.0f)) return 0; /* out, or NaN (t at infinity) */
  }
  return 1;
}

/* The test in double-float from the exact x0 = o - centre (TwoSum) and
 * exact products of the float data: the cold path of robust mode. The
 * roots stay in double-float for the box test. */
CR_COLD CR_FUNC int Quadric_IntersectDf(const real org[3], const real dir[3], const Quadric* s, real tmin, real tmax,
                                        real* tHit)
{
  Df x[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) x[i] = Df_SumF(org[i], -s->center[i]);
  /* Q's rows as indices into q: xx yy zz xy xz yz. */
  const int row[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
  Df a = Df_F(0.0f), bh = Df_F(0.0f), c = Df_F(s->j);
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    Df qd = Df_F(0.0f), u = Df_F(s->l[i]);
    CR_UNROLL for (int k = 0; k < 3; ++k) {
      const float qik = s->q[row[i][k]];
      qd = Df_Add(qd, Df_ProdF(qik, dir[k]));
      u = Df_Add(u, Df_MulF(x[k], qik));
    }
    a = Df_Add(a, Df_MulF(qd, dir[i]));
    bh = Df_Add(bh, Df_MulF(u, dir[i]));
    c = Df_Add(c, Df_Mul(x[i], Df_Add(u, Df_F(s->l[i]))));
  }
  const Df disc = Df_Sub(Df_Mul(bh, bh), Df_Mul(a, c));
  if (disc.hi < 0.0f) return 0;
  if (a.hi == 0.0f && bh.hi == 0.0f) return 0; /* no root, or every t (a line on the surface) */
  /* The roots kept in double-float for the box test. */
  Df r0, r1;
  Df_QuadraticRootsDf(a, bh, c, disc, &r0, &r1);
  if (r1.hi < r0.hi || !(r0.hi == r0.hi)) {
    const Df tr = r0;
    r0 = r1;
    r1 = tr;
  }
  if (r0.hi >= tmin && r0.hi <= tmax && Quadric_InBoxDf(s, x, dir, r0)) {
    *tHit = r0.hi;
    return 1;
  }
  if (r1.hi >= tmin && r1.hi <= tmax && Quadric_InBoxDf(s, x, dir, r1)) {
    *tHit = r1.hi;
    return 1;
  }
  return 0;
}

/* Whether root t, within e of its true value, may lie in [tmin, tmax] while
 * e exceeds 2^-17 (|o|/|d| + |t|), the bound robust mode keeps within the
 * checker's tolerance. NaN (a = 0: the root q / a at infinity with a
 * possibly nonzero) counts as "may". */
CR_FUNC int Quadric_RootNeedsDf(real t, real e, real oScale, real tmin, real tmax)
{
  if (e <= 0x1.0p-17f * (oScale + fabs(t))) return 0;
  return !(t + e < tmin || t - e > tmax);
}
#endif

/* Nearest root in [tmin, tmax] inside the clip box. */
CR_FUNC int Quadric_Intersect(const Ray* r, const Quadric* s, real tmin, real tmax, real* tHit)
{
  real x0[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) x0[i] = r->org[i] - (real)s->center[i];
  real qd[3], u[3];
  Quadric_MulQ(s->q, r->dir, qd);
  Quadric_MulQ(s->q, x0, u);
  CR_UNROLL for (int i = 0; i < 3; ++i) u[i] = u[i] + (real)s->l[i];
  const real a = Dot3(r->dir, qd);
  const real bh = Dot3(r->dir, u);
  const real c = x0[0] * (u[0] + (real)s->l[0]) + x0[1] * (u[1] + (real)s->l[1]) + x0[2] * (u[2] + (real)s->l[2]) +
                 (real)s->j;
  const real disc = bh * bh - a * c;
#if !defined(CR_FAST) && !defined(CR_FP64)
  {
    /* The scales: the same sums over absolute values. */
    real ad[3], ax[3], us[3];
    float aq[6];
    CR_UNROLL for (int i = 0; i < 3; ++i) {
      ad[i] = fabs(r->dir[i]);
      ax[i] = fabs(x0[i]);
    }
    CR_UNROLL for (int i = 0; i < 6; ++i) aq[i] = fabs(s->q[i]);
    real qs[3];
    Quadric_MulQ(aq, ad, qs);
    Quadric_MulQ(aq, ax, us);
    CR_UNROLL for (int i = 0; i < 3; ++i) us[i] = us[i] + fabs(s->l[i]);
    const real aS = Dot3(ad, qs);
    const real bS = Dot3(ad, us);
    const real cS = ax[0] * (us[0] + fabs(s->l[0])) + ax[1] * (us[1] + fabs(s->l[1])) +
                    ax[2] * (us[2] + fabs(s->l[2])) + fabs(s->j);
    const real ea = 0x1.0p-21f * aS, eb = 0x1.4p-21f * bS, ec = 0x1.8p-21f * cS;
    const real ed = 2.0f * fabs(bh) * eb + fabs(a) * ec + fabs(c) * ea + 0x1.0p-22f * (bh * bh + fabs(a * c));
    if (disc < -ed) return 0; /* a miss for certain */
    /* Undecided or nearly (within 4 times its error: the square root's
     * error bound below needs disc - ed >= 3 disc / 4), or a degenerate form
     * (a = bh = 0): double-float. NaN and overflow fall through to it. */
    if (!(disc > 4.0f * ed) || (a == 0.0f && bh == 0.0f))
      return Quadric_IntersectDf(r->org, r->dir, s, tmin, tmax, tHit);
    const real sq = copysign(sqrt(disc), bh);
    const real q = -(bh + sq);
    const real t0 = q / a, t1 = c / q;
    const real eq = eb + 0x1.2p-1f * ed / fabs(sq) + 0x1.0p-24f * fabs(q);
    const real rq = eq / fabs(q) + 0x1.0p-24f;
    /* a = 0 with no error (aS = 0: a ray along a cylinder's axis) puts the
     * root q / a exactly at infinity. */
    const real e0 = ea == 0.0f ? fabs(t0) * rq : fabs(t0) * (rq + ea / fabs(a));
    const real e1 = ec / fabs(q) + fabs(t1) * rq;
    const real oScale = fmax(fabs(r->org[0]), fmax(fabs(r->org[1]), fabs(r->org[2]))) /
                        fmax(ad[0], fmax(ad[1], ad[2]));
    if (Quadric_RootNeedsDf(t0, e0, oScale, tmin, tmax) || Quadric_RootNeedsDf(t1, e1, oScale, tmin, tmax) ||
        Quadric_BoxUndecided(s, x0, r->dir, fmin(t0, t1), fmax(t0, t1), fmax(e0, e1), tmin, tmax))
      return Quadric_IntersectDf(r->org, r->dir, s, tmin, tmax, tHit);
    return Quadric_Pick(s, x0, r->dir, fmin(t0, t1), fmax(t0, t1), tmin, tmax, tHit);
  }
#else
  if (disc < (real)0.0f) return 0;
  const real sq = copysign(sqrt(disc), bh);
  const real q = -(bh + sq);
  if (q == (real)0.0f) return 0; /* a = bh = 0, or a tangent through the origin's level */
  const real t0 = q / a, t1 = c / q;
  return Quadric_Pick(s, x0, r->dir, fmin(t0, t1), fmax(t0, t1), tmin, tmax, tHit);
#endif
}

/* The uniform form of the dispatch (CR_PRIM_TYPES): no barycentrics. */
CR_FUNC int Quadric_Test(const Ray* r, const Quadric* s, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
  return Quadric_Intersect(r, s, tmin, tmax, tHit);
}
/* A copy of a quadric in global memory (field by field). */
CR_FUNC Quadric Quadric_Load(CR_GLOBAL const Quadric* p)
{
  Quadric s;
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    s.center[i] = p->center[i];
    s.extent[i] = p->extent[i];
    s.l[i] = p->l[i];
  }
  CR_UNROLL for (int i = 0; i < 6; ++i) s.q[i] = p->q[i];
  s.j = p->j;
  return s;
}

#endif /* CELLRAY_KERNELS_QUADRIC_H */
