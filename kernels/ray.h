/* Ray and hit state shared by every traversal, and the kernels' arithmetic
 * type `real`: double in fp64 mode (CR_FP64), else float. Every kernel
 * header includes what it uses and compiles on its own, as OpenCL C (at
 * file scope) and as C++ (in the namespace of the including unit, which
 * instantiates the kernels of one precision mode: host/scalar/
 * kernel_instance.inc, one unit per mode; the SIMD units, robust; the
 * Embree user geometry, robust). A unit holds one instance: the headers'
 * guards are never undone. */
#ifndef CELLRAY_KERNELS_RAY_H
#define CELLRAY_KERNELS_RAY_H
#include "types.h"

#ifdef CR_FP64
typedef double real;
#else
typedef float real;
#endif

/* A ray prepared for traversal: inverse direction for slab tests (1/+-0 is
 * +-inf on purpose) and the shear constants of the watertight triangle test
 * (Woop, Benthin & Wald 2013, section 3). */
typedef struct {
  real org[3];
  real dir[3];
  real inv[3];
  real tmin;
  real tmax;
  real sx, sy, sz;
  int kx, ky, kz;
  /* An any-hit (occlusion) query: a primitive test may keep a float hit
   * that lies in range for certain, whatever its exact t, instead of taking
   * its double-float cold path (Sphere_NeedsDf, Cone_NeedsDf). 0 from
   * Ray_Init; set by the traversal that knows the query. */
  int anyHit;
  /* Time in the shutter interval [0, 1] (motion blur, kernels/motion.h): 0
   * from Ray_Init; set from the ray set's times where it has them. */
  real time;
} Ray;

/* Closest hit so far. g is a unified primitive index or CR_NO_HIT; t starts at
 * the ray's tmax, so a hit exactly at tmax is accepted (the interval is closed). */
typedef struct {
  real t;
  real u;
  real v;
  uint g;
} Hit;

/* Havran's per-ray measures: intersection tests (N_IT), traversal steps
 * (N_TS: nodes or cells visited), leaves visited (N_ETS), empty leaves
 * visited (N_EETS). */
typedef struct {
  uint nIT;
  uint nTS;
  uint nLeaves;
  uint nEmptyLeaves;
} TraceStats;

#ifdef CR_STATS
#define CR_COUNT(st, field) ((st)->field++)
#else
#define CR_COUNT(st, field) ((void)0)
#endif

CR_FUNC real Dot3(const real a[3], const real b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

CR_FUNC void Ray_Init(Ray* r, const RayRecord* rec)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    r->org[a] = (real)rec->org[a];
    r->dir[a] = (real)rec->dir[a];
    r->inv[a] = (real)1.0f / r->dir[a];
  }
  r->tmin = (real)rec->tmin;
  r->tmax = (real)rec->tmax;
  real ax = fabs(r->dir[0]), ay = fabs(r->dir[1]), az = fabs(r->dir[2]);
  int kz = (ax > ay) ? ((ax > az) ? 0 : 2) : ((ay > az) ? 1 : 2);
  int kx = kz + 1 == 3 ? 0 : kz + 1;
  int ky = kx + 1 == 3 ? 0 : kx + 1;
  if (CR_PICK3(r->dir, kz) < (real)0.0f) {
    int tmp = kx;
    kx = ky;
    ky = tmp;
  }
  r->kx = kx;
  r->ky = ky;
  r->kz = kz;
  r->anyHit = 0;
  r->time = (real)0.0f;
  r->sx = CR_PICK3(r->dir, kx) / CR_PICK3(r->dir, kz);
  r->sy = CR_PICK3(r->dir, ky) / CR_PICK3(r->dir, kz);
  r->sz = (real)1.0f / CR_PICK3(r->dir, kz);
}

CR_FUNC void Hit_Init(Hit* h, const Ray* r)
{
  h->t = r->tmax;
  h->u = (real)0.0f;
  h->v = (real)0.0f;
  h->g = CR_NO_HIT;
}

/* The order every backend uses to pick between two hits: nearer first, and
 * on an exact tie of t the lower unified index, so that traversal order never
 * changes the answer. */
CR_FUNC int Hit_Closer(real t, uint g, const Hit* h) { return t < h->t || (t == h->t && g < h->g); }

/* Parameter of the plane x[axis] = p along the ray. A ray lying in the plane
 * (direction component +-0) is treated as if the component were +-epsilon:
 * it is on the plane at t = 0 and leaves it at once. */
CR_FUNC real Ray_PlaneT(const Ray* r, int axis, real p)
{
  real t = (p - r->org[axis]) * r->inv[axis];
  return cr_isnan(t) ? (real)0.0f : t;
}

#endif /* CELLRAY_KERNELS_RAY_H */
