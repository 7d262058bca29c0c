/* The triangle (NFF `p`, `pp` and OBJ faces, split into triangles): its
 * robust cold paths (plane distance and edge functions in double-float) and
 * its watertight test. The layout is Triangle of kernels/types.h. */
#ifndef CELLRAY_KERNELS_TRIANGLE_H
#define CELLRAY_KERNELS_TRIANGLE_H
#include "numeric.h"

#ifndef CR_HAS_TRIANGLE
#define CR_HAS_TRIANGLE 1
#endif

/* Woop's inside test: the edge functions U, V, W have mixed signs (an edge
 * function of exactly 0 counts as inside for both neighbours). */
CR_FUNC int Triangle_EdgesMiss(real U, real V, real W)
{
  return (U < (real)0.0f || V < (real)0.0f || W < (real)0.0f) && (U > (real)0.0f || V > (real)0.0f || W > (real)0.0f);
}

#if !defined(CR_FAST) && !defined(CR_FP64)
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
  if (!Triangle_PlaneInexact(np0, np1, np2)) return 0;
  /* Scaled by |nd| (one division fewer; the SIMD backend's form). */
  const real sum = (fabs(np0) + fabs(np1)) + fabs(np2);
  const real an = fabs(nd), tn = t * an;
  const real slack = 0.25f * fabs(tn) + 0x1.0p-20f * sum;
  return tn + slack >= tmin * an && tn - slack <= tmax * an;
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
/* Triangle_Intersect's cold path, one call for both of its refinements.
 * `degenerate`: a float hit whose three edge functions all lie within their
 * rounding (Triangle_EdgesUndecided): the triangle's projection is below
 * float's resolution at its distance from the ray origin (a small triangle
 * far away, or one seen edge-on), where two edges can round to 0 and the
 * third not: an "inside" at the plane's crossing, however far that lies
 * from the triangle. The three edges again in double-float
 * (Triangle_EdgesDf); returns 0 when they now miss. `nearPlane`
 * (Triangle_PlaneNeedsDf): t from Triangle_PlaneTDf. The SIMD backend runs
 * the two lane by lane (Triangle_EdgesDf, then the same tests). */
CR_COLD CR_FUNC int Triangle_HitRefine(const Ray* r, const Triangle* tri, int degenerate, int nearPlane, real* U,
                                       real* V, real* W, real* t)
{
  if (degenerate) {
    Triangle_EdgesDf(r, tri, U, V, W);
    if (Triangle_EdgesMiss(*U, *V, *W) || *U + *V + *W == (real)0.0f) return 0;
  }
  if (nearPlane) *t = Triangle_PlaneTDf(r->org, r->dir, tri);
  return 1;
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

#endif

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
  if (Triangle_EdgesMiss(U, V, W)) return 0;
  real det = U + V + W;
  if (det == (real)0.0f) return 0;
#ifndef CR_FP64
  /* Float hits only (a rule that fired on misses too would cost every test
   * the three norms). With all three edges below their rounding the ray
   * passes within float's resolution of the whole triangle or nowhere near
   * it: a true hit is marginal (inside the ray's tolerance, and no ray from
   * inside a mesh sees one), a false one can lie anywhere on the plane
   * (docs/TOLERANCE.md; Triangle_HitRefine below). A neighbour deciding the
   * shared edge in float may then disagree with this one, on marginal rays
   * only. */
  const int degenerate = Triangle_EdgesUndecided(Triangle_Norm1(CR_PICK3(A, kx), CR_PICK3(A, ky), CR_PICK3(A, kz)),
                                                 Triangle_Norm1(CR_PICK3(B, kx), CR_PICK3(B, ky), CR_PICK3(B, kz)),
                                                 Triangle_Norm1(CR_PICK3(C, kx), CR_PICK3(C, ky), CR_PICK3(C, kz)),
                                                 U, V, W);
#endif
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
  /* The origin near the triangle's plane relative to the shared vertex's
   * distance, and t may lie in [tmin, tmax] (elsewhere the float t is out of
   * range too, and the test misses whatever the edges say): t in
   * double-float. Away from the plane the crossing lies within a few ulps
   * of the distance of the triangle, and the float t stands
   * (docs/TOLERANCE.md). */
  const int nearPlane = Triangle_PlaneNeedsDf(np0, np1, np2, nd, t, tmin, tmax);
  /* One call site for both refinements (on gfx906 each call site costs
   * registers and a frame). */
  if (degenerate | nearPlane) {
    if (!Triangle_HitRefine(r, tri, degenerate, nearPlane, &U, &V, &W, &t)) return 0;
    det = U + V + W;
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

/* The uniform form of the dispatch (CR_PRIM_TYPES). */
CR_FUNC int Triangle_Test(const Ray* r, const Triangle* tri, real tmin, real tmax, real* tHit, real* uHit, real* vHit)
{
  return Triangle_Intersect(r, tri, tmin, tmax, tHit, uHit, vHit);
}
/* A copy of a triangle in global memory (field by field). */
CR_FUNC Triangle Triangle_Load(CR_GLOBAL const Triangle* p)
{
  Triangle t;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    t.v0[a] = p->v0[a];
    t.v1[a] = p->v1[a];
    t.v2[a] = p->v2[a];
  }
  t.flags = p->flags; /* CR_TRI_LONG_*: robust mode checks those edges */
  t.pad1 = 0u;
  t.pad2 = 0u;
  return t;
}

#endif /* CELLRAY_KERNELS_TRIANGLE_H */
