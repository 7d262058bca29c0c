/* The convex polyhedron (NFF extension `polyhedron N` and N planes
 * `a b c d`, docs/FORMATS.md): the surface of the solid where every
 * a x + b y + c z + d <= 0; the layout is Polyhedron of kernels/types.h, its
 * planes about a float centre c with normals of length about 1.
 *
 * Slab clipping (Kay & Kajiya 1986; Haines, "Fast Ray-Convex Polyhedron
 * Intersection", Graphics Gems II): along the ray a plane's value is
 * s + t e, with s = n . (o - c) + w and e = n . dir; a plane with e < 0 is
 * entered at t = -s / e, one with e > 0 left there. The ray is inside over
 * [largest entry, smallest exit]; the hit is the entry, or the exit for a
 * ray that starts inside (as the box, kernels/box.h). A ray parallel to a
 * plane (e = 0) misses the solid where s >= 0: a ray lying in a face's
 * plane misses, as it misses a box's face it lies in.
 *
 * Precision modes: `fast` and `fp64` evaluate s and e in `real` (fp64: each
 * product of two floats is exact in double, the sums round once or twice);
 * `robust` in float with error bounds, and where a bound leaves a decision
 * open, in double-float (kernels/numeric.h: o - c and the products are
 * exact, each sum keeps about 48 bits), so that every t, and every
 * comparison between an entry and an exit, is right to about 2^-44
 * relative whatever the coordinates' magnitude and however nearly the ray
 * runs along a face (Polyhedron_IntersectRobust below). */
#ifndef CELLRAY_KERNELS_POLYHEDRON_H
#define CELLRAY_KERNELS_POLYHEDRON_H
#include "numeric.h"

#ifndef CR_HAS_POLYHEDRON
#define CR_HAS_POLYHEDRON 1
#endif

/* Slab clipping in `real` (fast, fp64; the SIMD backend's fast form calls it
 * lane by lane). */
CR_FUNC int Polyhedron_IntersectR(const real org[3], const real dir[3], const Polyhedron* p, real tmin, real tmax,
                                  real* tHit)
{
  real x[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) x[i] = org[i] - (real)p->center[i];
  real tn = -CR_INF, tf = CR_INF;
  for (uint k = 0u; k < p->count; ++k) {
    const float* n = p->plane[k];
    const real s = ((real)n[0] * x[0] + (real)n[1] * x[1] + (real)n[2] * x[2]) + (real)n[3];
    const real e = (real)n[0] * dir[0] + (real)n[1] * dir[1] + (real)n[2] * dir[2];
    if (e == (real)0.0f) {
      if (!(s < (real)0.0f)) return 0;
      continue;
    }
    const real t = -s / e;
    if (e < (real)0.0f)
      tn = fmax(tn, t);
    else
      tf = fmin(tf, t);
  }
  if (!(tn <= tf)) return 0;
  const real t = tn >= tmin ? tn : tf;
  if (!(t >= tmin && t <= tmax)) return 0;
  *tHit = t;
  return 1;
}

#if !defined(CR_FAST) && !defined(CR_FP64)
/* a < b for double-floats (hi, then lo). */
CR_FUNC int Df_Less(Df a, Df b) { return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo); }

/* Slab clipping in double-float (robust; the SIMD backend's robust form
 * calls it lane by lane). */
CR_FUNC int Polyhedron_IntersectDf(const real org[3], const real dir[3], const Polyhedron* p, real tmin, real tmax,
                                   real* tHit)
{
  Df x[3], d[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    x[i] = Df_SumF(org[i], -p->center[i]);
    d[i] = Df_F(dir[i]);
  }
  Df tn = Df_F(-CR_INF), tf = Df_F(CR_INF);
  for (uint k = 0u; k < p->count; ++k) {
    const float* n = p->plane[k];
    const Df s = Df_Add(Df_Dot3F(x, n), Df_F(n[3]));
    const Df e = Df_Dot3F(d, n);
    if (e.hi == 0.0f) {
      if (!(s.hi < 0.0f)) return 0;
      continue;
    }
    /* Past float's range (a subnormal e): the infinite quotient itself. */
    const float q = -s.hi / e.hi;
    const Df t = fabs(q) <= CR_FLT_MAX ? Df_Div(Df_Neg(s), e) : Df_F(q);
    if (e.hi < 0.0f) {
      if (Df_Less(tn, t)) tn = t;
    } else if (Df_Less(t, tf)) {
      tf = t;
    }
  }
  if (Df_Less(tf, tn)) return 0;
  /* hi is the nearest float to hi + lo. */
  const real t = tn.hi >= tmin ? tn.hi : tf.hi;
  if (!(t >= tmin && t <= tmax)) return 0;
  *tHit = t;
  return 1;
}
#endif

#if !defined(CR_FAST) && !defined(CR_FP64)
/* Robust mode: slab clipping in float with a bound on each rounding error,
 * falling back to the double-float form above wherever a bound leaves a
 * decision open or the hit's t less accurate than 2^-21 |t| (about 8
 * ulps):
 * - x = o - m rounds once (u |x|); s = n . x + w then carries at most
 *   6u (|n| . |x| + |w|) < 2^-21 S, e = n . d at most 3u |n| . |d| < 2^-22 E
 *   (u = 2^-24);
 * - a plane whose e is within its bound of 0 (sign unknown, or parallel)
 *   goes to double-float;
 * - t = -s / e is off by at most (es + |t| ee) / (|e| - ee) + u |t|; the
 *   latest entry keeps the bound of its plane, or, where another entry lies
 *   within both bounds of it, the larger bound (the true latest entry is
 *   then within it of the float one), and likewise the earliest exit;
 * - double-float again where entry and exit, or the chosen t and tmin or
 *   tmax, lie within their bounds of each other.
 * The SIMD backend runs this same function lane by lane, so its bits are
 * these. */
CR_FUNC int Polyhedron_IntersectRobust(const real org[3], const real dir[3], const Polyhedron* p, real tmin,
                                       real tmax, real* tHit)
{
  real x[3], ax[3], ad[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    x[i] = org[i] - p->center[i];
    ax[i] = fabs(x[i]);
    ad[i] = fabs(dir[i]);
  }
  real tn = -CR_INF, tf = CR_INF, en = 0.0f, ef = 0.0f;
  for (uint k = 0u; k < p->count; ++k) {
    const float* n = p->plane[k];
    const real s = (n[0] * x[0] + n[1] * x[1] + n[2] * x[2]) + n[3];
    const real e = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
    const real es = 0x1.0p-21f * ((fabs(n[0]) * ax[0] + fabs(n[1]) * ax[1] + fabs(n[2]) * ax[2]) + fabs(n[3]));
    const real ee = 0x1.0p-22f * (fabs(n[0]) * ad[0] + fabs(n[1]) * ad[1] + fabs(n[2]) * ad[2]);
    if (!(fabs(e) > ee)) return Polyhedron_IntersectDf(org, dir, p, tmin, tmax, tHit);
    const real t = -s / e;
    const real et = (es + fabs(t) * ee) / (fabs(e) - ee) + 0x1.0p-24f * fabs(t);
    if (e < 0.0f) {
      if (t - et > tn + en) {
        tn = t;
        en = et;
      } else if (t + et >= tn - en) {
        tn = fmax(tn, t);
        en = fmax(en, et);
      }
    } else {
      if (t + et < tf - ef) {
        tf = t;
        ef = et;
      } else if (t - et <= tf + ef) {
        tf = fmin(tf, t);
        ef = fmax(ef, et);
      }
    }
  }
  /* A bounded solid: some plane is entered and some left; tn, tf finite. */
  if (tn - en > tf + ef) return 0; /* certainly apart */
  if (!(tn + en < tf - ef)) return Polyhedron_IntersectDf(org, dir, p, tmin, tmax, tHit);
  if (!(fabs(tn - tmin) > en)) return Polyhedron_IntersectDf(org, dir, p, tmin, tmax, tHit);
  const real t = tn >= tmin ? tn : tf;
  const real et = tn >= tmin ? en : ef;
  if (!(fabs(t - tmin) > et && fabs(t - tmax) > et)) return Polyhedron_IntersectDf(org, dir, p, tmin, tmax, tHit);
  if (!(t >= tmin && t <= tmax)) return 0;
  if (!(et <= 0x1.0p-21f * fabs(t))) return Polyhedron_IntersectDf(org, dir, p, tmin, tmax, tHit);
  *tHit = t;
  return 1;
}
#endif

CR_FUNC int Polyhedron_Test(const Ray* r, const Polyhedron* p, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
#if defined(CR_FAST) || defined(CR_FP64)
  return Polyhedron_IntersectR(r->org, r->dir, p, tmin, tmax, tHit);
#else
  return Polyhedron_IntersectRobust(r->org, r->dir, p, tmin, tmax, tHit);
#endif
}
/* A copy of a polyhedron in global memory: its planes only. */
CR_FUNC Polyhedron Polyhedron_Load(CR_GLOBAL const Polyhedron* p)
{
  Polyhedron s;
  CR_UNROLL for (int i = 0; i < 3; ++i) s.center[i] = p->center[i];
  s.count = p->count;
  CR_UNROLL for (int i = 0; i < 3; ++i) s.lo[i] = s.hi[i] = 0.0f;
  s.pad0 = s.pad1 = 0u;
  for (uint k = 0u; k < s.count; ++k) CR_UNROLL for (int i = 0; i < 4; ++i) s.plane[k][i] = p->plane[k][i];
  return s;
}

#endif /* CELLRAY_KERNELS_POLYHEDRON_H */
