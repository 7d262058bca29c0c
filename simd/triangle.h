// The triangle in the SIMD kernels: its pack (the scene's Triangle rows are
// read as they are), the lane-wise Triangle_Intersect of kernels/triangle.h
// (watertight and Moller-Trumbore) and its three forms (SimdTest<Triangle>,
// simd/prims.h).
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

// The plane normal is not stored (48 of 224 bytes a pack): the test
// computes it from the vertices when a lane passes the edge functions, the
// shortest edge (Triangle_PlaneNormal's choice) read from two pack-only bits
// of flags above Triangle.flags' own.
inline constexpr std::uint32_t kPackShortEdge1 = 1u << 8, kPackShortEdge2 = 1u << 9;
int PackShortEdge(const Triangle& t);  // Triangle_PlaneNormal's k (bvh_wide_builder.cpp)

template <int K>
struct TrianglePack {  // 44 K bytes
  float v[3][3][K];    // [vertex][axis][lane]
  std::uint32_t g[K];
  std::uint32_t flags[K];  // Triangle.flags (the CR_TRI_LONG_* bits are read) | kPackShortEdge*
};

template <>
struct SimdPrim<Triangle> {
  using Data = Triangle;
  template <int K>
  using Pack = TrianglePack<K>;
  static constexpr bool kDistanceTies = false;
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>& p, int l, const Data& t)
  {
    for (int a = 0; a < 3; ++a) {
      p.v[0][a][l] = t.v0[a];
      p.v[1][a][l] = t.v1[a];
      p.v[2][a][l] = t.v2[a];
    }
    const int k = PackShortEdge(t);
    p.flags[l] = t.flags | (k == 1 ? kPackShortEdge1 : 0u) | (k == 2 ? kPackShortEdge2 : 0u);
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// t = n . p / n . d with the products summed in Dot3's order (a ray with
// n . d == 0 joins `miss`); `nearPlane`: the
// lanes where Triangle_PlaneNeedsDf holds (n . p cancels by more than 16 and
// t may lie in [tmin, tmax]), computed as there, without a branch (most
// tests past the edge functions of a ray leaving a surface are inexact, and
// a branch on it mispredicts) and without a second division.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneDivN(const vfloat<N> n[3], const vfloat<N> p[3], const vfloat<N> dir[3],
                                            vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax, vbool<N>& nearPlane)
{
  const vfloat<N> nd = Dot3N<N>(n, dir);
  miss = miss | (nd == vfloat<N>(0.0f));
  const vfloat<N> np0 = n[0] * p[0], np1 = n[1] * p[1], np2 = n[2] * p[2];
  const vfloat<N> np = (np0 + np1) + np2;
  const vfloat<N> sum = (Abs(np0) + Abs(np1)) + Abs(np2);
  const vfloat<N> t = np / nd;
  const vfloat<N> an = Abs(nd), tn = t * an;
  const vfloat<N> slack = vfloat<N>(0.25f) * Abs(tn) + vfloat<N>(0x1.0p-20f) * sum;
  nearPlane = (sum > vfloat<N>(16.0f) * Abs(np)) & (tn + slack >= tmin * an) & (tn - slack <= tmax * an);
  return t;
}

// The distance along the ray to the triangle's plane, kernels/intersect.h's
// Triangle_Intersect step for step, given which edge is the shortest (k0:
// edge 0, k1: edge 1, else edge 2): the normal from that edge and its
// successor (edges from the stored vertices), the shared vertex relative to
// the origin; a plane-parallel ray (n.d == 0) sets `miss`. v0..v2, org, dir
// in world axis order.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneKN(const vfloat<N> v0[3], const vfloat<N> v1[3], const vfloat<N> v2[3],
                                          vbool<N> k0, vbool<N> k1, const vfloat<N> org[3], const vfloat<N> dir[3],
                                          vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax, vbool<N>& nearPlane)
{
  // Edge k, its successor, and the vertex they share:
  // k 0: e0, e1, v1; k 1: e1, e2, v2; k 2: e2, e0, v0.
  vfloat<N> ea[3], eb[3], p[3];
  for (int i = 0; i < 3; ++i) {
    const vfloat<N> e0 = v1[i] - v0[i], e1 = v2[i] - v1[i], e2 = v0[i] - v2[i];
    ea[i] = Select(k0, e0, Select(k1, e1, e2));
    eb[i] = Select(k0, e1, Select(k1, e2, e0));
    p[i] = Select(k0, v1[i] - org[i], Select(k1, v2[i] - org[i], v0[i] - org[i]));
  }
  vfloat<N> n[3];
  n[0] = ea[1] * eb[2] - ea[2] * eb[1];
  n[1] = ea[2] * eb[0] - ea[0] * eb[2];
  n[2] = ea[0] * eb[1] - ea[1] * eb[0];
  return Triangle_PlaneDivN<N>(n, p, dir, miss, tmin, tmax, nearPlane);
}

// The same, the shortest edge found as Triangle_PlaneNormal finds it.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneTN(const vfloat<N> v0[3], const vfloat<N> v1[3], const vfloat<N> v2[3],
                                          const vfloat<N> org[3], const vfloat<N> dir[3], vbool<N>& miss,
                                          vfloat<N> tmin, vfloat<N> tmax, vbool<N>& nearPlane)
{
  vfloat<N> e0[3], e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    e0[i] = v1[i] - v0[i];
    e1[i] = v2[i] - v1[i];
    e2[i] = v0[i] - v2[i];
  }
  const vfloat<N> l0 = Dot3N<N>(e0, e0), l1 = Dot3N<N>(e1, e1), l2 = Dot3N<N>(e2, e2);
  // k = (l0 <= l1) ? ((l0 <= l2) ? 0 : 2) : ((l1 <= l2) ? 1 : 2)
  const vbool<N> k0 = (l0 <= l1) & (l0 <= l2);
  const vbool<N> k1 = AndNot(l1 <= l2, l0 <= l1);
  return Triangle_PlaneKN<N>(v0, v1, v2, k0, k1, org, dir, miss, tmin, tmax, nearPlane);
}

// Triangle_PlaneTN for one triangle against N rays (packets): the normal
// depends on the triangle only, so it comes once from the scalar kernels'
// Triangle_PlaneNormal (the same float operations, no contraction:
// simd/CMakeLists.txt), which gives every lane Triangle_PlaneTN's bits.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneT1N(const Triangle& tri, const vfloat<N> org[3], const vfloat<N> dir[3],
                                           vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax, vbool<N>& nearPlane)
{
  float nf[3];
  const int shared = Triangle_PlaneNormal(&tri, nf);
  const float* vk = shared == 0 ? tri.v0 : (shared == 1 ? tri.v1 : tri.v2);
  const vfloat<N> n[3] = {vfloat<N>(nf[0]), vfloat<N>(nf[1]), vfloat<N>(nf[2])};
  vfloat<N> p[3];
  for (int i = 0; i < 3; ++i) p[i] = vfloat<N>(vk[i]) - org[i];
  return Triangle_PlaneDivN<N>(n, p, dir, miss, tmin, tmax, nearPlane);
}

// Plane sources for Triangle_WatertightN: T(org, dir, miss, tmin, tmax, nearPlane) gives
// the distance to the triangle's plane, Tri(l) lane l's triangle (for the
// double-float cold path). Vertices already in registers (a transposed
// group), a TrianglePack's [vertex][axis][lane] floats, or one triangle for
// every lane (packets).
template <int N>
struct VecPlane {
  const vfloat<N> (&vtx)[3][4];
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax,
              vbool<N>& nearPlane) const
  {
    return Triangle_PlaneTN<N>(vtx[0], vtx[1], vtx[2], org, dir, miss, tmin, tmax, nearPlane);
  }
  // Lanes whose triangle has long edges (the flags word rides in v0's
  // fourth float).
  unsigned LongEdgeLanes() const { return MaskedLanes(vtx[0][3], CR_TRI_LONG_EDGES); }
  unsigned FlagLanes(std::uint32_t bit) const { return MaskedLanes(vtx[0][3], bit); }
  Triangle Tri(int l) const
  {
    Triangle t{};
    for (int i = 0; i < 3; ++i) {
      t.v0[i] = vtx[0][i][l];
      t.v1[i] = vtx[1][i][l];
      t.v2[i] = vtx[2][i][l];
    }
    t.flags = __builtin_bit_cast(std::uint32_t, vtx[0][3][l]);
    return t;
  }
};
template <int N>
struct PackPlane {
  const float (&pv)[3][3][N];
  const std::uint32_t (&flags)[N];
  // Triangle_PlaneTN from the pack's vertices and shortest edges.
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax,
              vbool<N>& nearPlane) const
  {
    const vint<N> fl = vint<N>::Load(flags);
    const vbool<N> k1 = vbool<N>::FromBits(MaskedLanes(fl, kPackShortEdge1));
    const vbool<N> k2 = vbool<N>::FromBits(MaskedLanes(fl, kPackShortEdge2));
    const vbool<N> k0 = !(k1 | k2);
    vfloat<N> v[3][3];
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) v[j][i] = vfloat<N>::Load(pv[j][i]);
    return Triangle_PlaneKN<N>(v[0], v[1], v[2], k0, k1, org, dir, miss, tmin, tmax, nearPlane);
  }
  unsigned LongEdgeLanes() const { return MaskedLanes(vint<N>::Load(flags), CR_TRI_LONG_EDGES); }
  unsigned FlagLanes(std::uint32_t bit) const { return MaskedLanes(vint<N>::Load(flags), bit); }
  Triangle Tri(int l) const
  {
    Triangle t{};
    for (int i = 0; i < 3; ++i) {
      t.v0[i] = pv[0][i][l];
      t.v1[i] = pv[1][i][l];
      t.v2[i] = pv[2][i][l];
    }
    t.flags = flags[l] & ~(kPackShortEdge1 | kPackShortEdge2);
    return t;
  }
};
template <int N>
struct OnePlane {
  const Triangle& tri;
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vfloat<N> tmin, vfloat<N> tmax,
              vbool<N>& nearPlane) const
  {
    return Triangle_PlaneT1N<N>(tri, org, dir, miss, tmin, tmax, nearPlane);
  }
  unsigned LongEdgeLanes() const { return tri.flags & CR_TRI_LONG_EDGES ? (1u << N) - 1u : 0u; }
  unsigned FlagLanes(std::uint32_t bit) const { return tri.flags & bit ? (1u << N) - 1u : 0u; }
  Triangle Tri(int) const { return tri; }
};

// The lanes of `bits` run a scalar kernel edge routine on their edge
// functions: refine(ray, tri, l, &U, &V, &W) with the lane's ray prepared as
// the scalar kernels prepare it (Ray_Init) and its triangle from the plane
// source (Triangle_RefineEdges, Triangle_EdgesDf of kernels/intersect.h).
// Lane l of a packet as the scalar kernels' Ray over [0, inf) (the cold
// paths read its origin, direction and shear only).
template <int N>
CR_SIMD_INLINE Ray LaneRay(const vfloat<N> org[3], const vfloat<N> dir[3], int l)
{
  RayRecord rec{};
  Lane3<N>(org, l, rec.org);
  Lane3<N>(dir, l, rec.dir);
  rec.tmax = __builtin_inff();
  Ray ray;
  Ray_Init(&ray, &rec);
  return ray;
}
template <int N>
struct EdgeFunctions {
  vfloat<N> U, V, W;
};
template <int N, class PlaneFn, class Refine>
__attribute__((noinline, cold)) EdgeFunctions<N> Triangle_EdgeLanesN(unsigned bits, PlaneFn plane,
                                                                     const vfloat<N> org[3], const vfloat<N> dir[3],
                                                                     vfloat<N> U, vfloat<N> V, vfloat<N> W,
                                                                     Refine refine)
{
  alignas(32) float u[N], v[N], w[N];
  U.Store(u);
  V.Store(v);
  W.Store(w);
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    const Ray ray = LaneRay<N>(org, dir, l);
    const Triangle tri = plane.Tri(l);
    refine(ray, tri, l, &u[l], &v[l], &w[l]);
  }
  return {vfloat<N>::Load(u), vfloat<N>::Load(v), vfloat<N>::Load(w)};
}

// Lanes near their triangle's plane whose t may lie in range: the second
// half of the scalar kernels' Triangle_HitRefine (Triangle_PlaneTDf) lane by
// lane. Out of line and cold.
template <int N, class PlaneFn>
__attribute__((noinline, cold)) vfloat<N> Triangle_NearPlaneLanesN(unsigned bits, PlaneFn plane,
                                                                   const vfloat<N> org[3], const vfloat<N> dir[3],
                                                                   vfloat<N> t)
{
  alignas(32) float tt[N];
  t.Store(tt);
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    const Ray ray = LaneRay<N>(org, dir, l);
    const Triangle tri = plane.Tri(l);
    tt[l] = Triangle_PlaneTDf(ray.org, ray.dir, &tri);
  }
  return vfloat<N>::Load(tt);
}

// Robust Triangle_Intersect (Woop, Benthin & Wald 2013) after the
// translation: A[j], B[j], C[j] are the vertices minus the ray origin in the
// ray's permuted axes (j = 0, 1, 2 for kx, ky, kz); s[] = sx, sy, sz.
// plane.T(org, dir, miss, tmin, tmax, nearPlane) gives the distance to the triangle's plane
// (Triangle_PlaneTN; the plane sources above); it runs only when some lane
// passes the edge tests (most tests miss before), so the world-order
// vertices are not loaded or kept in registers for the others.
template <int N, class PlaneFn>
CR_SIMD_INLINE vbool<N> Triangle_WatertightN(const vfloat<N> A[3], const vfloat<N> B[3], const vfloat<N> C[3],
                                             const vfloat<N> s[3], PlaneFn&& plane, const vfloat<N> org[3],
                                             const vfloat<N> dir[3], vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit,
                                             vfloat<N>& uHit, vfloat<N>& vHit, vbool<N> lanes)
{
  const vfloat<N> Ax = A[0] - s[0] * A[2], Ay = A[1] - s[1] * A[2];
  const vfloat<N> Bx = B[0] - s[0] * B[2], By = B[1] - s[1] * B[2];
  const vfloat<N> Cx = C[0] - s[0] * C[2], Cy = C[1] - s[1] * C[2];
  vfloat<N> U = Cx * By - Cy * Bx;
  vfloat<N> V = Ax * Cy - Ay * Cx;
  vfloat<N> W = Bx * Ay - By * Ax;
  // Triangles with long edges: a flagged edge within its rounding bound
  // (Triangle_LongEdgeUndecided) takes the scalar kernels'
  // Triangle_RefineEdges, lane by lane.
  if (plane.LongEdgeLanes()) {
    const vfloat<N> nA = (Abs(A[0]) + Abs(A[1])) + Abs(A[2]);
    const vfloat<N> nB = (Abs(B[0]) + Abs(B[1])) + Abs(B[2]);
    const vfloat<N> nC = (Abs(C[0]) + Abs(C[1])) + Abs(C[2]);
    const vfloat<N> k(0x1.0p-18f);
    const unsigned undecided = ((plane.FlagLanes(CR_TRI_LONG_U) & (Abs(U) <= k * (nB * nC)).Bits()) |
                                (plane.FlagLanes(CR_TRI_LONG_V) & (Abs(V) <= k * (nC * nA)).Bits()) |
                                (plane.FlagLanes(CR_TRI_LONG_W) & (Abs(W) <= k * (nA * nB)).Bits())) &
                               lanes.Bits();
    if (undecided) {
      const EdgeFunctions<N> e = Triangle_EdgeLanesN<N>(
          undecided, plane, org, dir, U, V, W,
          [=](const Ray& ray, const Triangle& tri, int l, float* u, float* v, float* w) {
            Triangle_RefineEdges(&ray, &tri, nA[l], nB[l], nC[l], u, v, w);
          });
      U = e.U;
      V = e.V;
      W = e.W;
    }
  }
  const vfloat<N> zero(0.0f);
  // Triangle_EdgesMiss lane-wise.
  const auto edgesMiss = [zero](vfloat<N> u, vfloat<N> v, vfloat<N> w) {
    return ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
  };
  vbool<N> miss = edgesMiss(U, V, W) | !lanes;
  vfloat<N> det = U + V + W;
  miss = miss | (det == zero);
  // Most tests miss here: skip the division when all do.
  if (All(miss)) {
    tHit = uHit = vHit = zero;
    return vbool<N>(false);
  }
  // t from the triangle's plane, as kernels/triangle.h computes it (in world
  // axis order, which the sums' rounding depends on). Where n . p cancels
  // (the origin near the plane: Triangle_PlaneInexact) and t may lie in
  // [tmin, tmax], as there: Triangle_PlaneTDf, lane by lane. Only lanes whose
  // t may lie in range need it: elsewhere the float t is out of range too,
  // and the lane misses (a shadow ray leaving a face, t just behind its
  // origin, stays here).
  vbool<N> nearPlane;
  vfloat<N> t = plane.T(org, dir, miss, tmin, tmax, nearPlane);
  nearPlane = AndNot(nearPlane, miss);
  if (Any(nearPlane)) t = Triangle_NearPlaneLanesN<N>(nearPlane.Bits(), plane, org, dir, t);
  vbool<N> hit = AndNot((t >= tmin) & (t <= tmax), miss);
  // Hits whose three edge functions all lie within their rounding
  // (Triangle_EdgesUndecided: a projection below float's resolution) take
  // the first half of the scalar kernels' Triangle_HitRefine, lane by lane:
  // the edges in double-float (Triangle_EdgesDf), then the same sign and zero
  // tests as above. Only hits in range need it (the scalar code refines
  // before its range test, but a lane out of range misses whatever the
  // edges say, and t does not depend on them), so the norms are computed
  // for fewer lanes than every float hit.
  if (Any(hit)) {
    const vfloat<N> nA = (Abs(A[0]) + Abs(A[1])) + Abs(A[2]);
    const vfloat<N> nB = (Abs(B[0]) + Abs(B[1])) + Abs(B[2]);
    const vfloat<N> nC = (Abs(C[0]) + Abs(C[1])) + Abs(C[2]);
    const vfloat<N> k(0x1.0p-19f);
    const unsigned degenerate =
        ((Abs(U) <= k * (nB * nC)) & (Abs(V) <= k * (nC * nA)) & (Abs(W) <= k * (nA * nB)) & hit).Bits();
    if (degenerate) {
      const EdgeFunctions<N> e = Triangle_EdgeLanesN<N>(
          degenerate, plane, org, dir, U, V, W,
          [](const Ray& ray, const Triangle& tri, int, float* u, float* v, float* w) {
            Triangle_EdgesDf(&ray, &tri, u, v, w);
          });
      U = e.U;
      V = e.V;
      W = e.W;
      det = U + V + W;
      hit = AndNot(hit, edgesMiss(U, V, W) | (det == zero));
    }
  }
  const vfloat<N> invDet = vfloat<N>(1.0f) / det;
  tHit = t;
  uHit = V * invDet;
  vHit = W * invDet;
  return hit;
}

// Fast Triangle_Intersect (Moller & Trumbore 1997, |det| >= 1e-9).
// Comparisons keep the scalar code's NaN behaviour; a NaN t passes its range
// test there and is then refused by Hit_Closer, so it is refused here.
template <int N>
CR_SIMD_INLINE vbool<N> Triangle_MollerTrumboreN(const vfloat<N> v0[3], const vfloat<N> v1[3], const vfloat<N> v2[3],
                                                 const vfloat<N> org[3], const vfloat<N> dir[3], vfloat<N> tmin,
                                                 vfloat<N> tmax, vfloat<N>& tHit, vfloat<N>& uHit, vfloat<N>& vHit)
{
  vfloat<N> e1[3], e2[3], tv[3], pv[3], qv[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = v1[i] - v0[i];
    e2[i] = v2[i] - v0[i];
    tv[i] = org[i] - v0[i];
  }
  pv[0] = dir[1] * e2[2] - dir[2] * e2[1];
  pv[1] = dir[2] * e2[0] - dir[0] * e2[2];
  pv[2] = dir[0] * e2[1] - dir[1] * e2[0];
  const vfloat<N> det = Dot3N<N>(e1, pv);
  const vfloat<N> zero(0.0f), one(1.0f);
  vbool<N> miss = Abs(det) < vfloat<N>(1e-9f);
  const vfloat<N> invDet = one / det;
  const vfloat<N> u = Dot3N<N>(tv, pv) * invDet;
  miss = miss | (u < zero) | (u > one);
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  const vfloat<N> v = Dot3N<N>(dir, qv) * invDet;
  miss = miss | (v < zero) | (u + v > one);
  const vfloat<N> t = Dot3N<N>(e2, qv) * invDet;
  miss = miss | (t < tmin) | (t > tmax) | IsNaN(t);
  tHit = t;
  uHit = u;
  vHit = v;
  return !miss;
}


template <>
struct SimdTest<Triangle> {
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> m,
                                        vfloat<N> tmax,
                                        vfloat<N>& t, vfloat<N>& u, vfloat<N>& v)
  {
    const Triangle& tri = PrimData<Triangle>(sc)[Prim_Local(&sc.ranges, CR_PRIM_TRIANGLE, g)];
    if constexpr (kFast) {
      vfloat<N> v0[3], v1[3], v2[3];
      for (int i = 0; i < 3; ++i) {
        v0[i] = vfloat<N>(tri.v0[i]);
        v1[i] = vfloat<N>(tri.v1[i]);
        v2[i] = vfloat<N>(tri.v2[i]);
      }
      return Triangle_MollerTrumboreN<N>(v0, v1, v2, P.org, P.dir, P.tmin, tmax, t, u, v);
    } else {
      vfloat<N> A[3], B[3], C[3];
      if (P.kUniform) {
        // Every lane has the same axis permutation (coherent packets): the
        // permuted components are plain broadcasts.
        for (int j = 0; j < 3; ++j) {
          A[j] = vfloat<N>(tri.v0[P.kScalar[j]]) - P.orgK[j];
          B[j] = vfloat<N>(tri.v1[P.kScalar[j]]) - P.orgK[j];
          C[j] = vfloat<N>(tri.v2[P.kScalar[j]]) - P.orgK[j];
        }
      } else {
        for (int j = 0; j < 3; ++j) {
          A[j] = PermuteXYZ(tri.v0, P.sel[j]) - P.orgK[j];
          B[j] = PermuteXYZ(tri.v1, P.sel[j]) - P.orgK[j];
          C[j] = PermuteXYZ(tri.v2, P.sel[j]) - P.orgK[j];
        }
      }
      return Triangle_WatertightN<N>(A, B, C, P.s, OnePlane<N>{tri}, P.org, P.dir, P.tmin, tmax, t, u, v, m);
    }
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene&, const TrianglePack<K>& pk, vbool<K> valid, const PackRay<K>& pr,
                                      vfloat<K> tmax, vfloat<K>& t, vfloat<K>& u, vfloat<K>& v)
  {
    if constexpr (kFast) {
      vfloat<K> v0[3], v1[3], v2[3];
      for (int i = 0; i < 3; ++i) {
        v0[i] = vfloat<K>::Load(pk.v[0][i]);
        v1[i] = vfloat<K>::Load(pk.v[1][i]);
        v2[i] = vfloat<K>::Load(pk.v[2][i]);
      }
      return Triangle_MollerTrumboreN<K>(v0, v1, v2, pr.org, pr.dir, pr.tmin, tmax, t, u, v);
    } else {
      vfloat<K> A[3], B[3], C[3];
      for (int j = 0; j < 3; ++j) {
        A[j] = vfloat<K>::Load(pk.v[0][pr.k[j]]) - pr.orgK[j];
        B[j] = vfloat<K>::Load(pk.v[1][pr.k[j]]) - pr.orgK[j];
        C[j] = vfloat<K>::Load(pk.v[2][pr.k[j]]) - pr.orgK[j];
      }
      return Triangle_WatertightN<K>(A, B, C, pr.s, PackPlane<K>{pk.v, pk.flags}, pr.org, pr.dir, pr.tmin, tmax, t, u,
                                     v, valid);
    }
  }
  // Each vertex is a 16-byte row (x, y, z, flags or pad).
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>& u, vfloat<4>& v)
  {
    const Triangle* tri[4];
    for (int l = 0; l < 4; ++l) tri[l] = &PrimData<Triangle>(sc)[Prim_Local(&sc.ranges, CR_PRIM_TRIANGLE, g[l])];
    const float* rows[4];
    vfloat<4> vtx[3][4];  // [vertex][axis]
    for (int l = 0; l < 4; ++l) rows[l] = tri[l]->v0;
    LoadTransposed4(rows, vtx[0]);
    for (int l = 0; l < 4; ++l) rows[l] = tri[l]->v1;
    LoadTransposed4(rows, vtx[1]);
    for (int l = 0; l < 4; ++l) rows[l] = tri[l]->v2;
    LoadTransposed4(rows, vtx[2]);
    if constexpr (kFast) {
      return Triangle_MollerTrumboreN<4>(vtx[0], vtx[1], vtx[2], pr.org, pr.dir, pr.tmin, tmax, t, u, v);
    } else {
      vfloat<4> A[3], B[3], C[3];
      for (int j = 0; j < 3; ++j) {
        A[j] = vtx[0][pr.k[j]] - pr.orgK[j];
        B[j] = vtx[1][pr.k[j]] - pr.orgK[j];
        C[j] = vtx[2][pr.k[j]] - pr.orgK[j];
      }
      return Triangle_WatertightN<4>(A, B, C, pr.s, VecPlane<4>{vtx}, pr.org, pr.dir, pr.tmin, tmax, t, u, v, vbool<4>(true));
    }
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
