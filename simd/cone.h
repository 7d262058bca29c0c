// The open cone in the SIMD kernels: its ray-independent terms (ConeData),
// its pack, the lane-wise Cone_Intersect of kernels/cone.h and its three
// forms (SimdTest<Cone>, simd/prims.h).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "simd/simd_kernels.h"

namespace cr::simd {

// Cone with the ray-independent terms of Cone_Intersect (kernels/cone.h)
// computed once, in float, in the kernel's operation order, so the SIMD
// kernels reproduce its rounding bit for bit: w = (apex - base) / H,
// H = |apex - base|, r0 = base radius, k = (apex radius - r0) / H.
struct ConeData {  // 48 bytes
  float base[3];
  float H;
  float w[3];
  float r0;
  float k;
  float pad[3];
};
static_assert(sizeof(ConeData) == 48);

template <int K>
struct ConePack {  // 40 K bytes
  float base[3][K];
  float w[3][K];
  float H[K];
  float r0[K];
  float k[K];
  std::uint32_t g[K];
};

template <>
struct SimdPrim<Cone> {
  using Data = ConeData;
  template <int K>
  using Pack = ConePack<K>;
  static constexpr bool kDistanceTies = false;
  // The operations of Cone_Intersect in float, in its order (compiled
  // without FMA contraction, like the kernels).
  static void MakeData(const std::vector<Cone>& cones, std::vector<Data>& out)
  {
    out.resize(cones.size());
    for (std::size_t i = 0; i < cones.size(); ++i) {
      const Cone& c = cones[i];
      Data& d = out[i];
      float w[3];
      for (int a = 0; a < 3; ++a) {
        w[a] = c.apex[a] - c.base[a];
        d.base[a] = c.base[a];
      }
      d.H = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      for (int a = 0; a < 3; ++a) d.w[a] = w[a] / d.H;
      d.r0 = c.baseRadius;
      d.k = (c.apexRadius - d.r0) / d.H;
    }
  }
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>& p, int l, const Data& d)
  {
    for (int a = 0; a < 3; ++a) {
      p.base[a][l] = d.base[a];
      p.w[a][l] = d.w[a];
    }
    p.H[l] = d.H;
    p.r0[l] = d.r0;
    p.k[l] = d.k;
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// Cone_NeedsDf of kernels/cone.h, lane by lane, for the lanes not in `skip`
// (misses and the linear case, which the scalar test never asks about; a
// missing lane, disc < 0, would pass the cancellation rule and cost the
// windows of the whole vector).
template <int N>
CR_SIMD_INLINE vbool<N> Cone_NeedsDfN(vfloat<N> C, vfloat<N> cScale, vfloat<N> Bh, vfloat<N> disc, vfloat<N> ee,
                                      vfloat<N> xx, vfloat<N> q, vfloat<N> dl2, vfloat<N> oo, vfloat<N> k,
                                      vfloat<N> ds, vfloat<N> rb, vfloat<N> dd, vfloat<N> A,
                                      vfloat<N> t0, vfloat<N> t1, vfloat<N> tmin, vfloat<N> tmax, vfloat<N> os,
                                      vfloat<N> H, vbool<N> skip, bool anyHit)
{
  const vfloat<N> dScale = ee + xx;
  const vfloat<N> d2 = disc * (Bh * Bh + disc);
  const vfloat<N> ds2 = dScale * dScale;
  const vbool<N> inaccurate = AndNot(
      (cScale > vfloat<N>(8.0f) * Abs(C)) | (ds2 > vfloat<N>(64.0f) * d2) | (dl2 > vfloat<N>(64.0f) * oo), skip);
  if (None(inaccurate)) return inaccurate;
  const vfloat<N> ndl = Sqrt(dl2), nd = Sqrt(dd), noR = Sqrt(oo), kds = Abs(k * ds), ak = Abs(k), arb = Abs(rb);
  const vfloat<N> Ee = vfloat<N>(0x1.0p-20f) * ((ak * ndl + vfloat<N>(2.0f) * arb) * nd + kds * ndl);
  const vfloat<N> Ex = vfloat<N>(0x1.0p-19f) * ((ndl + noR) * nd);
  const vfloat<N> eDisc = vfloat<N>(2.0f) * Sqrt(dScale) * (Ee + Ex) + vfloat<N>(0x1.0p-21f) * dScale;
  const vfloat<N> eB = vfloat<N>(0x1.0p-20f) * (ndl * (nd + ak * kds) + noR * nd + kds * arb);
  const vfloat<N> eA = vfloat<N>(0x1.0p-19f) * (dd + kds * (kds + ak * nd));
  const vfloat<N> iq = vfloat<N>(1.0f) / Abs(q);
  const vfloat<N> rel =
      (eDisc / (vfloat<N>(2.0f) * Sqrt(disc)) + eB) * iq + eA / Abs(A) + vfloat<N>(0x1.0p-20f);
  const vbool<N> always = (ds2 > vfloat<N>(0x1.0p36f) * d2) | (dl2 > vfloat<N>(0x1.0p36f) * oo) |
                          !(disc > vfloat<N>(0.0f)) |
                          !((eDisc < vfloat<N>(0.25f) * disc) & (rel < vfloat<N>(0.0625f)));
  const vfloat<N> e = vfloat<N>(0x1.0p-20f) * (cScale + ndl * (noR + vfloat<N>(4.0f) * Abs(k * rb))) * iq;
  const vfloat<N> m = Select(vfloat<N>(16.0f) * q * q >= A * cScale, vfloat<N>(0.0f), FMax(Abs(t0), Abs(t1)));
  const vfloat<N> s0 = rel * FMax(Abs(t0), m) + e, s1 = rel * FMax(Abs(t1), m) + e;
  const vfloat<N> a0 = os + t0 * ds, a1 = os + t1 * ds;
  const vfloat<N> ea0 = vfloat<N>(0x1.0p-20f) * (ndl + Abs(t0) * nd + H) + Abs(ds) * s0;
  const vfloat<N> ea1 = vfloat<N>(0x1.0p-20f) * (ndl + Abs(t1) * nd + H) + Abs(ds) * s1;
  const vfloat<N> zero(0.0f);
  vbool<N> window =
      ((t0 + s0 >= tmin) & (t0 - s0 <= tmax) & (a0 + ea0 >= zero) & (a0 - ea0 <= H)) |
      ((t1 + s1 >= tmin) & (t1 - s1 <= tmax) & (a1 + ea1 >= zero) & (a1 - ea1 <= H));
  if (anyHit)
    window = AndNot(window, ((t0 - s0 > tmin) & (t0 + s0 < tmax) & (a0 - ea0 > zero) & (a0 + ea0 < H)) |
                                ((t1 - s1 > tmin) & (t1 + s1 < tmax) & (a1 - ea1 > zero) & (a1 + ea1 < H)));
  return inaccurate & (always | window);
}

// Cone_Intersect with the per-cone terms of ConeData (w unit axis, H, r0, k).
// dl = org - base. coneOf(l) is lane l's cone as the scene holds it (nullptr
// for a lane that holds none), for the double-float cold path
// (Cone_IntersectDf), which must start from the stored apex and base.
template <bool kFast, int N, class ConeOf>
CR_SIMD_INLINE vbool<N> Cone_IntersectN(const vfloat<N> org[3], const vfloat<N> dl[3], const vfloat<N> dir[3],
                                        const vfloat<N> w[3], vfloat<N> H, vfloat<N> r0, vfloat<N> k, vfloat<N> tmin,
                                        vfloat<N> tmax, vfloat<N>& tHit, bool anyHit, vbool<N> lanes, ConeOf&& coneOf)
{
  const vfloat<N> zero(0.0f);
  vbool<N> miss = (!(H > zero)) | !lanes;
  const vfloat<N> ds = Dot3N<N>(dir, w);
  const vfloat<N> os = Dot3N<N>(dl, w);
  vfloat<N> dR[3], oR[3];
  for (int i = 0; i < 3; ++i) {
    dR[i] = dir[i] - ds * w[i];
    oR[i] = dl[i] - os * w[i];
  }
  const vfloat<N> rb = r0 + k * os;
  const vfloat<N> A = Dot3N<N>(dR, dR) - k * k * ds * ds;
  const vfloat<N> Bh = Dot3N<N>(oR, dR) - k * ds * rb;
  const vfloat<N> oo = Dot3N<N>(oR, oR);
  const vfloat<N> C = oo - rb * rb;
  // A == 0: the linear case.
  const vbool<N> linear = A == zero;
  vfloat<N> t0, t1;
  vbool<N> quadMiss, refine(false);
  if constexpr (kFast) {
    const vfloat<N> disc4 = vfloat<N>(4.0f) * Bh * Bh - vfloat<N>(4.0f) * A * C;
    quadMiss = disc4 < zero;
    const vfloat<N> sq = Sqrt(disc4);
    const vfloat<N> ta = (vfloat<N>(-2.0f) * Bh - sq) / (vfloat<N>(2.0f) * A);
    const vfloat<N> tb = (vfloat<N>(-2.0f) * Bh + sq) / (vfloat<N>(2.0f) * A);
    t0 = FMin(ta, tb);
    t1 = FMax(ta, tb);
  } else {
    vfloat<N> e[3], x[3];
    for (int i = 0; i < 3; ++i) e[i] = rb * dR[i] - k * ds * oR[i];
    x[0] = oR[1] * dR[2] - oR[2] * dR[1];
    x[1] = oR[2] * dR[0] - oR[0] * dR[2];
    x[2] = oR[0] * dR[1] - oR[1] * dR[0];
    const vfloat<N> ee = Dot3N<N>(e, e), xx = Dot3N<N>(x, x);
    const vfloat<N> disc = ee - xx;
    quadMiss = disc < zero;
    // A discriminant within its rounding of 0: decided in double-float.
    const vbool<N> undecided = AndNot(quadMiss & (-disc <= vfloat<N>(0x1.0p-20f) * (ee + xx)), miss | linear);
    // Skip the square root and divisions when every lane misses already.
    if (None(undecided) && All(miss | (linear & (Bh == zero)) | AndNot(quadMiss, linear))) {
      tHit = zero;
      return vbool<N>(false);
    }
    vfloat<N> q;
    Quadratic_RootsN<N>(A, Bh, C, oo + rb * rb, disc, t0, t1, q);
    refine = Cone_NeedsDfN<N>(C, oo + rb * rb, Bh, disc, ee, xx, q, Dot3N<N>(dl, dl), oo, k, ds, rb,
                              Dot3N<N>(dir, dir), A, t0, t1, tmin, tmax, os, H, miss | linear | quadMiss, anyHit) |
             undecided;
  }
  // The linear root, past the early exit above (most tests end there, and
  // a division left before it stalls every one of them).
  if (Any(linear)) {
    const vfloat<N> tLin = -C / (vfloat<N>(2.0f) * Bh);
    t0 = Select(linear, tLin, t0);
    t1 = Select(linear, tLin, t1);
  }
  miss = miss | (linear & (Bh == zero)) | AndNot(quadMiss, linear);
  const vfloat<N> s0 = os + t0 * ds;
  const vfloat<N> s1 = os + t1 * ds;
  const vbool<N> ok0 = (t0 >= tmin) & (t0 <= tmax) & (s0 >= zero) & (s0 <= H);
  const vbool<N> ok1 = (t1 >= tmin) & (t1 <= tmax) & (s1 >= zero) & (s1 <= H);
  tHit = Select(ok0, t0, t1);
  vbool<N> ok = AndNot(ok0 | ok1, miss);
  if constexpr (!kFast) {
    if (Any(refine)) {
      const RefinedLanes<N> r = RefineLanesN<N>(refine.Bits(), [=](int l, float* th) {
        const Cone* cn = coneOf(l);
        if (!cn) return false;
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        return Cone_IntersectDf(o, d, cn, tmin[l], tmax[l], th) != 0;
      }, tHit, ok);
      tHit = r.t;
      ok = r.ok;
    }
  }
  return ok;
}


template <>
struct SimdTest<Cone> {
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> m,
                                        vfloat<N> tmax,
                                        vfloat<N>& t, vfloat<N>&, vfloat<N>&)
  {
    const std::uint32_t i = Prim_Local(&sc.ranges, CR_PRIM_CONE, g);
    const ConeData& cd = PrimData<Cone>(sc)[i];
    vfloat<N> dl[3], w[3];
    for (int a = 0; a < 3; ++a) {
      dl[a] = P.org[a] - vfloat<N>(cd.base[a]);
      w[a] = vfloat<N>(cd.w[a]);
    }
    const Cone* cone = &ScenePrims<Cone>(sc)[i];
    return Cone_IntersectN<kFast, N>(P.org, dl, P.dir, w, vfloat<N>(cd.H), vfloat<N>(cd.r0), vfloat<N>(cd.k), P.tmin,
                                     tmax, t, P.anyHit, m, [cone](int) { return cone; });
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene& sc, const ConePack<K>& pk, vbool<K> valid,
                                      const PackRay<K>& pr, vfloat<K> tmax, vfloat<K>& t, vfloat<K>&, vfloat<K>&)
  {
    vfloat<K> dl[3], w[3];
    for (int i = 0; i < 3; ++i) {
      dl[i] = pr.org[i] - vfloat<K>::Load(pk.base[i]);
      w[i] = vfloat<K>::Load(pk.w[i]);
    }
    return Cone_IntersectN<kFast, K>(pr.org, dl, pr.dir, w, vfloat<K>::Load(pk.H), vfloat<K>::Load(pk.r0),
                                     vfloat<K>::Load(pk.k), pr.tmin, tmax, t, pr.anyHit, valid,
                                     [&sc, &pk, bits = valid.Bits()](int l) {
                                       return bits >> l & 1u
                                                  ? &ScenePrims<Cone>(sc)[Prim_Local(&sc.ranges, CR_PRIM_CONE, pk.g[l])]
                                                  : nullptr;
                                     });
  }
  // ConeData rows: (base, H), (w, r0), (k, pad).
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>&, vfloat<4>&)
  {
    const ConeData* cd[4];
    for (int l = 0; l < 4; ++l) cd[l] = &PrimData<Cone>(sc)[Prim_Local(&sc.ranges, CR_PRIM_CONE, g[l])];
    const float* rows[4];
    vfloat<4> r0[4], r1[4], r2[4];
    for (int l = 0; l < 4; ++l) rows[l] = cd[l]->base;
    LoadTransposed4(rows, r0);
    for (int l = 0; l < 4; ++l) rows[l] = cd[l]->w;
    LoadTransposed4(rows, r1);
    for (int l = 0; l < 4; ++l) rows[l] = &cd[l]->k;
    LoadTransposed4(rows, r2);
    vfloat<4> dl[3];
    for (int a = 0; a < 3; ++a) dl[a] = pr.org[a] - r0[a];
    return Cone_IntersectN<kFast, 4>(pr.org, dl, pr.dir, r1, r0[3], r1[3], r2[0], pr.tmin, tmax, t, pr.anyHit,
                                     vbool<4>(true), [&](int l) {
      return &ScenePrims<Cone>(sc)[Prim_Local(&sc.ranges, CR_PRIM_CONE, g[l])];
    });
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
