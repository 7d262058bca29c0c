/* The SDF block (NFF extension `sdf` ... `sdf end`, docs/FORMATS.md): a
 * surface given by a signed distance function, traced by sphere tracing
 * (Hart 1996) with over-relaxation (Keinert et al. 2014, "Enhanced Sphere
 * Tracing"); the layout is Sdf of kernels/types.h: a postfix program of at
 * most CR_SDF_MAX_OPS operations about a float centre, a bound (the block's
 * box: the surface outside it is not part of the primitive), the hit
 * threshold eps, the step budget and the relaxation factor.
 *
 * The march starts where the ray enters the bound (or at tmin) and walks
 * t += w f / |d| with w the relaxation (1 <= w < 2); a relaxed step whose
 * unbounding sphere does not overlap the last one's may have stepped over
 * the surface, so the march goes back to the last safe step and continues
 * with w = 1. It hits where f < eps; it misses when it leaves the bound or
 * [tmin, tmax], or when the step budget runs out (the block's in fast mode,
 * CR_SDF_ROBUST_STEPS in robust and fp64). A ray that starts (at
 * tmin, inside the bound) within eps of the surface first leaves that
 * shell (steps of eps along the ray, at most CR_SDF_SHELL_STEPS, not
 * counted in the budget),
 * so that a shadow ray from a hit point does not find the surface it starts
 * on; the side it then finds itself on (outside or inside the solid) is the
 * side it marches from.
 *
 * Precision modes: `fast` reports the first t where f < eps; `robust` and
 * `fp64` (in double) refine it with up to CR_SDF_REFINE plain steps
 * t += f / |d|, each kept only if it brings the point nearer the surface
 * (onto it for a hit away from grazing; to the closest approach for a ray
 * that passes within eps), so that the reported t lies well within eps of
 * the surface. The SIMD backend runs Sdf_March lane by lane.
 *
 * Only what a scene uses: CR_SDF_OPS, a mask of (1 << op), keeps the code
 * of the operations the scene's blocks contain (default: all). */
#ifndef CELLRAY_KERNELS_SDF_H
#define CELLRAY_KERNELS_SDF_H
#include "numeric.h"

#ifndef CR_HAS_SDF
#define CR_HAS_SDF 1
#endif
#ifndef CR_SDF_OPS
#define CR_SDF_OPS 0xFFFFu
#endif
#define CR_SDF_USES(op) ((CR_SDF_OPS >> (op)) & 1u)
#ifndef CR_SDF_REFINE
#define CR_SDF_REFINE 8
#endif
/* Steps of eps to leave the shell a ray starts in, apart from the budget
 * (a ray leaving the surface at a grazing angle needs about 1 / cos of
 * them); a ray still in the shell after them misses. */
#define CR_SDF_SHELL_STEPS 4096u
/* The step budget of robust and fp64 marches, whatever the block's (the
 * fp64 reference's; host/prims/sdf.cpp). */
#define CR_SDF_ROBUST_STEPS 1048576u

CR_FUNC real Sdf_Len3(real x, real y, real z) { return sqrt(x * x + y * y + z * z); }
CR_FUNC real Sdf_Len2(real x, real y) { return sqrt(x * x + y * y); }

/* The program's value at x (coordinates about the centre). */
CR_FUNC real Sdf_Eval(const Sdf* s, const real x[3])
{
  real st[CR_SDF_MAX_STACK];
  real ps[CR_SDF_MAX_STACK][3];
  real p[3];
  int sp = 0, pp = 0;
  CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = x[i];
  st[0] = CR_INF;
  for (uint k = 0u; k < s->count; ++k) {
    const uint op = s->op[k].op;
    const float* a = s->op[k].a;
    real d = (real)0.0f;
    int leaf = 1;
    if (CR_SDF_USES(CR_SDF_SPHERE) && op == CR_SDF_SPHERE) {
      d = Sdf_Len3(p[0] - (real)a[0], p[1] - (real)a[1], p[2] - (real)a[2]) - (real)a[3];
    } else if (CR_SDF_USES(CR_SDF_BOX) && op == CR_SDF_BOX) {
      /* half extents a[3..5], edges rounded by a[6] */
      real q[3], out = (real)0.0f, in = -CR_INF;
      CR_UNROLL for (int i = 0; i < 3; ++i) {
        q[i] = fabs(p[i] - (real)a[i]) - (real)a[3 + i] + (real)a[6];
        out += fmax(q[i], (real)0.0f) * fmax(q[i], (real)0.0f);
        in = fmax(in, q[i]);
      }
      d = sqrt(out) + fmin(in, (real)0.0f) - (real)a[6];
    } else if (CR_SDF_USES(CR_SDF_TORUS) && op == CR_SDF_TORUS) {
      /* about the y axis: ring radius a[3], tube radius a[4] */
      const real qx = Sdf_Len2(p[0] - (real)a[0], p[2] - (real)a[2]) - (real)a[3];
      d = Sdf_Len2(qx, p[1] - (real)a[1]) - (real)a[4];
    } else if (CR_SDF_USES(CR_SDF_CAPSULE) && op == CR_SDF_CAPSULE) {
      /* segment a[0..2] to a[3..5], radius a[6] */
      real pa[3], ba[3];
      CR_UNROLL for (int i = 0; i < 3; ++i) {
        pa[i] = p[i] - (real)a[i];
        ba[i] = (real)a[3 + i] - (real)a[i];
      }
      const real bb = ba[0] * ba[0] + ba[1] * ba[1] + ba[2] * ba[2];
      const real h = bb > (real)0.0f ? fmin(fmax((pa[0] * ba[0] + pa[1] * ba[1] + pa[2] * ba[2]) / bb, (real)0.0f),
                                            (real)1.0f)
                                     : (real)0.0f;
      d = Sdf_Len3(pa[0] - ba[0] * h, pa[1] - ba[1] * h, pa[2] - ba[2] * h) - (real)a[6];
    } else if (CR_SDF_USES(CR_SDF_CYLINDER) && op == CR_SDF_CYLINDER) {
      /* capped, about the y axis: radius a[3], half height a[4] */
      const real dx = Sdf_Len2(p[0] - (real)a[0], p[2] - (real)a[2]) - (real)a[3];
      const real dy = fabs(p[1] - (real)a[1]) - (real)a[4];
      d = fmin(fmax(dx, dy), (real)0.0f) + Sdf_Len2(fmax(dx, (real)0.0f), fmax(dy, (real)0.0f));
    } else {
      leaf = 0;
    }
    if (leaf) {
      st[sp++] = d;
      continue;
    }
    if (op == CR_SDF_UNION || op == CR_SDF_INTERSECTION || op == CR_SDF_DIFFERENCE || op == CR_SDF_SMOOTH_UNION) {
      const real b = st[--sp];
      const real l = st[sp - 1];
      real r = fmin(l, b);
      if (CR_SDF_USES(CR_SDF_INTERSECTION) && op == CR_SDF_INTERSECTION) r = fmax(l, b);
      if (CR_SDF_USES(CR_SDF_DIFFERENCE) && op == CR_SDF_DIFFERENCE) r = fmax(l, -b);
      if (CR_SDF_USES(CR_SDF_SMOOTH_UNION) && op == CR_SDF_SMOOTH_UNION) {
        /* quadratic smooth minimum of radius k = a[0] (Quilez) */
        const real kr = (real)a[0];
        const real h = fmax(kr - fabs(l - b), (real)0.0f) / kr;
        r = fmin(l, b) - h * h * kr * (real)0.25f;
      }
      st[sp - 1] = r;
    } else if (CR_SDF_USES(CR_SDF_REPEAT) && op == CR_SDF_REPEAT) {
      /* period a[0..2] (0: none on that axis), copies -a[3+i]..a[3+i] */
      CR_UNROLL for (int i = 0; i < 3; ++i) {
        ps[pp][i] = p[i];
        const real c = (real)a[i];
        if (c > (real)0.0f) p[i] -= c * fmin(fmax(rint(p[i] / c), -(real)a[3 + i]), (real)a[3 + i]);
      }
      ++pp;
    } else if (CR_SDF_USES(CR_SDF_REPEAT) && op == CR_SDF_END_REPEAT) {
      --pp;
      CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = ps[pp][i];
    }
  }
  return st[0];
}

/* A march is a call in OpenCL programs: PoCL 3.1's inliner (LLVM 15,
 * CloneAndPruneFunctionInto) crashed building the packet kernels of a
 * program with every primitive type when it was inlined. */
#ifdef CR_OPENCL
#define CR_SDF_CALL __attribute__((noinline))
#else
#define CR_SDF_CALL
#endif

CR_FUNC real Sdf_EvalCounted(const Sdf* s, const real x[3], uint* evals)
{
  *evals += 1u;
  return Sdf_Eval(s, x);
}

/* Sphere tracing in `real`, the hit refined by up to `refine` plain steps
 * (fast: 0; robust and fp64: CR_SDF_REFINE); *evals counts the distance
 * evaluations (host/prims/sdf_steps.cpp reports them per ray). */
CR_SDF_CALL CR_FUNC int Sdf_MarchCounted(const real org[3], const real dir[3], const Sdf* s, real tmin, real tmax,
                                         int refine, real* tHit, uint* evals)
{
  /* The bound's slabs (fmin/fmax pass over the NaN of a ray in a face). */
  real t0 = tmin, t1 = tmax;
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    const real ta = ((real)s->lo[i] - org[i]) / dir[i];
    const real tb = ((real)s->hi[i] - org[i]) / dir[i];
    t0 = fmax(t0, fmin(ta, tb));
    t1 = fmin(t1, fmax(ta, tb));
  }
  if (!(t0 <= t1)) return 0;
  real x[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) x[i] = org[i] - (real)s->center[i];
  const real len = Sdf_Len3(dir[0], dir[1], dir[2]);
  if (!(len > (real)0.0f)) return 0;
  const real inv = (real)1.0f / len;
  const real eps = (real)s->eps;
  real t = t0, p[3];
  uint n = 0u;
  /* A ray that starts inside the bound first leaves the eps shell it may
   * start in (one that enters the bound from outside marches from there). */
  CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = x[i] + t * dir[i];
  real f = Sdf_EvalCounted(s, p, evals);
  if (t0 <= tmin) {
    for (uint m = 0u; fabs(f) < eps; ++m) {
      if (m == CR_SDF_SHELL_STEPS) return 0;
      t += eps * inv;
      if (t > t1) return 0;
      CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = x[i] + t * dir[i];
      f = Sdf_EvalCounted(s, p, evals);
    }
  }
  const real side = f < (real)0.0f ? (real)-1.0f : (real)1.0f;
  real w = (real)s->relax, tPrev = t, rPrev = (real)0.0f;
  /* The budget stops fast mode's march; robust and fp64 (refine > 0) march
   * on to the reference's budget: a ray grazing a surface at just over eps
   * takes steps of about eps, and one the budget stopped would miss a
   * surface it goes on to hit (rim of a smooth union: 300 steps at eps
   * 0.0005 where the block allowed 256). Rays that need them are rare. */
  const uint budget = refine > 0 ? CR_SDF_ROBUST_STEPS : s->steps;
  for (; n < budget; ++n) {
    if (!(t <= t1)) {
      /* A relaxed step past the end may have passed the surface too: the
       * safe step from the last point decides. */
      if (w > (real)1.0f && tPrev + rPrev <= t1 && t > tPrev) {
        t = tPrev + rPrev;
        w = (real)1.0f;
        continue;
      }
      return 0;
    }
    CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = x[i] + t * dir[i];
    const real r = side * Sdf_EvalCounted(s, p, evals) * inv; /* distance along the ray */
    if (w > (real)1.0f && t > tPrev && fabs(r) + rPrev < t - tPrev) {
      /* the relaxed step may have passed the surface: back to the safe one */
      t = tPrev + rPrev;
      w = (real)1.0f;
      continue;
    }
    if (r < eps * inv) {
      /* Plain steps while they bring the point nearer the surface: onto it
       * for a hit, to the closest approach for a ray that passes within
       * eps (never farther from the surface than where the march stopped). */
      real step = r, best = fabs(r);
      for (int k = 0; k < refine && step != (real)0.0f; ++k) {
        const real tn = t + step;
        CR_UNROLL for (int i = 0; i < 3; ++i) p[i] = x[i] + tn * dir[i];
        const real rn = side * Sdf_EvalCounted(s, p, evals) * inv;
        if (!(fabs(rn) < best)) break;
        t = tn;
        best = fabs(rn);
        step = rn;
      }
      if (!(t >= t0 && t <= t1)) return 0;
      *tHit = t;
      return 1;
    }
    tPrev = t;
    rPrev = r;
    t += w * r;
  }
  return 0;
}

/* The march without its count. */
CR_FUNC int Sdf_March(const real org[3], const real dir[3], const Sdf* s, real tmin, real tmax, int refine,
                                  real* tHit)
{
  uint evals = 0u;
  return Sdf_MarchCounted(org, dir, s, tmin, tmax, refine, tHit, &evals);
}

CR_FUNC int Sdf_Test(const Ray* r, const Sdf* s, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
#ifdef CR_FAST
  return Sdf_March(r->org, r->dir, s, tmin, tmax, 0, tHit);
#else
  return Sdf_March(r->org, r->dir, s, tmin, tmax, CR_SDF_REFINE, tHit);
#endif
}

/* A copy of a block in global memory: its operations only. */
CR_FUNC Sdf Sdf_Load(CR_GLOBAL const Sdf* p)
{
  Sdf s;
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    s.center[i] = p->center[i];
    s.lo[i] = p->lo[i];
    s.hi[i] = p->hi[i];
  }
  s.count = p->count;
  s.eps = p->eps;
  s.steps = p->steps;
  s.relax = p->relax;
  s.pad[0] = s.pad[1] = s.pad[2] = 0u;
  for (uint k = 0u; k < s.count; ++k) {
    s.op[k].op = p->op[k].op;
    CR_UNROLL for (int i = 0; i < 7; ++i) s.op[k].a[i] = p->op[k].a[i];
  }
  return s;
}

#endif /* CELLRAY_KERNELS_SDF_H */
