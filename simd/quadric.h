// The clipped quadric in the SIMD kernels: its pack (the 16 floats of the
// scene's Quadric rows, lane by lane), the lane-wise Quadric_Intersect of
// kernels/quadric.h (the same operations in the same order, so every lane
// gets the scalar kernel's bits) and its three forms (SimdTest<Quadric>,
// simd/prims.h). Lanes whose robust error bounds call for it take the
// scalar kernels' double-float test (Quadric_IntersectDf).
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

template <int K>
struct QuadricPack {  // 68 K bytes
  float f[16][K];     // the Quadric's floats in layout order
  std::uint32_t g[K];
};

template <>
struct SimdPrim<Quadric> {
  using Data = Quadric;
  template <int K>
  using Pack = QuadricPack<K>;
  static constexpr bool kDistanceTies = false;
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>& p, int l, const Data& s)
  {
    const float* f = &s.center[0];
    for (int i = 0; i < 16; ++i) p.f[i][l] = f[i];
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// A quadric per lane: the layout's 16 floats as vectors.
template <int N>
struct QuadricN {
  vfloat<N> f[16];  // center[3], j, extent[3], q[6], l[3]
  const vfloat<N>* center() const { return f; }
  const vfloat<N>& j() const { return f[3]; }
  const vfloat<N>* extent() const { return f + 4; }
  const vfloat<N>* q() const { return f + 7; }
  const vfloat<N>* l() const { return f + 13; }
  Quadric Lane(int l) const
  {
    Quadric s;
    float* out = &s.center[0];
    for (int i = 0; i < 16; ++i) out[i] = f[i][l];
    return s;
  }
};

// Quadric_MulQ: Q v for the symmetric Q (xx yy zz xy xz yz).
template <int N>
CR_SIMD_INLINE void Quadric_MulQN(const vfloat<N> q[6], const vfloat<N> v[3], vfloat<N> out[3])
{
  out[0] = q[0] * v[0] + q[3] * v[1] + q[4] * v[2];
  out[1] = q[3] * v[0] + q[1] * v[1] + q[5] * v[2];
  out[2] = q[4] * v[0] + q[5] * v[1] + q[2] * v[2];
}

// Quadric_Intersect lane by lane. Only the lanes in `lanes` take the cold
// path.
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Quadric_IntersectN(const vfloat<N> org[3], const vfloat<N> dir[3], const QuadricN<N>& s,
                                           vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit, vbool<N> lanes)
{
  vfloat<N> x0[3], qd[3], u[3];
  for (int i = 0; i < 3; ++i) x0[i] = org[i] - s.center()[i];
  Quadric_MulQN<N>(s.q(), dir, qd);
  Quadric_MulQN<N>(s.q(), x0, u);
  for (int i = 0; i < 3; ++i) u[i] = u[i] + s.l()[i];
  const vfloat<N> a = Dot3N<N>(dir, qd);
  const vfloat<N> bh = Dot3N<N>(dir, u);
  const vfloat<N> c = x0[0] * (u[0] + s.l()[0]) + x0[1] * (u[1] + s.l()[1]) + x0[2] * (u[2] + s.l()[2]) + s.j();
  const vfloat<N> disc = bh * bh - a * c;
  const vfloat<N> zero(0.0f);
  vbool<N> miss, refine(false);
  vfloat<N> t0, t1;
  if constexpr (kFast) {
    miss = disc < zero;
    const vfloat<N> sq = CopySign(Sqrt(disc), bh);
    const vfloat<N> q = -(bh + sq);
    miss = miss | (q == zero);
    t0 = q / a;
    t1 = c / q;
  } else {
    vfloat<N> ad[3], ax[3], aq[6], qs[3], us[3];
    for (int i = 0; i < 3; ++i) {
      ad[i] = Abs(dir[i]);
      ax[i] = Abs(x0[i]);
    }
    for (int i = 0; i < 6; ++i) aq[i] = Abs(s.q()[i]);
    Quadric_MulQN<N>(aq, ad, qs);
    Quadric_MulQN<N>(aq, ax, us);
    for (int i = 0; i < 3; ++i) us[i] = us[i] + Abs(s.l()[i]);
    const vfloat<N> aS = Dot3N<N>(ad, qs);
    const vfloat<N> bS = Dot3N<N>(ad, us);
    const vfloat<N> cS = ax[0] * (us[0] + Abs(s.l()[0])) + ax[1] * (us[1] + Abs(s.l()[1])) +
                         ax[2] * (us[2] + Abs(s.l()[2])) + Abs(s.j());
    const vfloat<N> ea = vfloat<N>(0x1.0p-21f) * aS, eb = vfloat<N>(0x1.4p-21f) * bS;
    const vfloat<N> ec = vfloat<N>(0x1.8p-21f) * cS;
    const vfloat<N> ed = vfloat<N>(2.0f) * Abs(bh) * eb + Abs(a) * ec + Abs(c) * ea +
                         vfloat<N>(0x1.0p-22f) * (bh * bh + Abs(a * c));
    miss = disc < -ed;
    if (None(AndNot(lanes, miss))) {
      tHit = zero;
      return vbool<N>(false);
    }
    const vbool<N> cold = (!(disc > vfloat<N>(4.0f) * ed)) | ((a == zero) & (bh == zero));
    const vfloat<N> sq = CopySign(Sqrt(disc), bh);
    const vfloat<N> q = -(bh + sq);
    t0 = q / a;
    t1 = c / q;
    const vfloat<N> eq = eb + vfloat<N>(0x1.2p-1f) * ed / Abs(sq) + vfloat<N>(0x1.0p-24f) * Abs(q);
    const vfloat<N> rq = eq / Abs(q) + vfloat<N>(0x1.0p-24f);
    const vfloat<N> e0 = Select(ea == zero, Abs(t0) * rq, Abs(t0) * (rq + ea / Abs(a)));
    const vfloat<N> e1 = ec / Abs(q) + Abs(t1) * rq;
    const vfloat<N> oScale = FMax(Abs(org[0]), FMax(Abs(org[1]), Abs(org[2]))) / FMax(ad[0], FMax(ad[1], ad[2]));
    auto needs = [&](vfloat<N> t, vfloat<N> e) {
      const vbool<N> accurate = e <= vfloat<N>(0x1.0p-17f) * (oScale + Abs(t));
      return AndNot(!((t + e < tmin) | (t - e > tmax)), accurate);
    };
    // Quadric_BoxUndecided: the first root in range whose box test is not
    // certainly "out" lies within its error of a face.
    const vfloat<N> lo = FMin(t0, t1), hi = FMax(t0, t1), e = FMax(e0, e1);
    auto boxTest = [&](vfloat<N> t, vbool<N>* outp) {  // Quadric_InBoxRobust: out (if asked), else undecided
      vbool<N> und(false), out(false);
      for (int i = 0; i < 3; ++i) {
        const vfloat<N> td = t * dir[i];
        const vfloat<N> p = Abs(x0[i] + td);
        const vfloat<N> ep = e * ad[i] + vfloat<N>(0x1.0p-22f) * (ax[i] + Abs(td));
        out = out | (p - ep > s.extent()[i]);
        und = und | (p + ep >= s.extent()[i]);
      }
      if (outp) *outp = out;
      return AndNot(und, out);
    };
    vbool<N> out0;
    const vbool<N> in0 = (lo >= tmin) & (lo <= tmax), in1 = (hi >= tmin) & (hi <= tmax);
    const vbool<N> und0 = in0 & boxTest(lo, &out0);
    const vbool<N> und1 = in1 & boxTest(hi, nullptr);
    const vbool<N> boxUndecided = und0 | AndNot(und1, AndNot(in0, out0));  // lo undecided, or not a hit and hi undecided
    refine = AndNot(lanes & (cold | needs(t0, e0) | needs(t1, e1) | boxUndecided), miss);
  }
  const vfloat<N> lo = FMin(t0, t1), hi = FMax(t0, t1);
  auto inBox = [&](vfloat<N> t) {
    vbool<N> in = Abs(x0[0] + t * dir[0]) <= s.extent()[0];
    for (int i = 1; i < 3; ++i) in = in & (Abs(x0[i] + t * dir[i]) <= s.extent()[i]);
    return in;
  };
  const vbool<N> ok0 = (lo >= tmin) & (lo <= tmax) & inBox(lo);
  const vbool<N> ok1 = (hi >= tmin) & (hi <= tmax) & inBox(hi);
  tHit = Select(ok0, lo, hi);
  vbool<N> ok = AndNot(ok0 | ok1, miss);
  if constexpr (!kFast) {
    if (Any(refine)) {
      const RefinedLanes<N> r = RefineLanesN<N>(refine.Bits(), [&s, org, dir, tmin, tmax](int l, float* th) {
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        const Quadric sl = s.Lane(l);
        return Quadric_IntersectDf(o, d, &sl, tmin[l], tmax[l], th) != 0;
      }, tHit, ok);
      tHit = r.t;
      ok = r.ok;
    }
  }
  return ok;
}

template <>
struct SimdTest<Quadric> {
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> lanes,
                                        vfloat<N> tmax, vfloat<N>& t, vfloat<N>&, vfloat<N>&)
  {
    const Quadric& s = PrimData<Quadric>(sc)[Prim_Local(&sc.ranges, CR_PRIM_QUADRIC, g)];
    QuadricN<N> v;
    const float* f = &s.center[0];
    for (int i = 0; i < 16; ++i) v.f[i] = vfloat<N>(f[i]);
    return Quadric_IntersectN<kFast, N>(P.org, P.dir, v, P.tmin, tmax, t, lanes);
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene&, const QuadricPack<K>& pk, vbool<K> valid,
                                      const PackRay<K>& pr, vfloat<K> tmax, vfloat<K>& t, vfloat<K>&, vfloat<K>&)
  {
    QuadricN<K> v;
    for (int i = 0; i < 16; ++i) v.f[i] = vfloat<K>::Load(pk.f[i]);
    return Quadric_IntersectN<kFast, K>(pr.org, pr.dir, v, pr.tmin, tmax, t, valid);
  }
  // Quadric rows: (centre, j), (extent, q xx), (q yy zz xy xz), (q yz, l).
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>&, vfloat<4>&)
  {
    const float* rows[4];
    QuadricN<4> v;
    for (int r = 0; r < 4; ++r) {
      for (int l = 0; l < 4; ++l)
        rows[l] = &PrimData<Quadric>(sc)[Prim_Local(&sc.ranges, CR_PRIM_QUADRIC, g[l])].center[0] + 4 * r;
      LoadTransposed4(rows, v.f + 4 * r);
    }
    return Quadric_IntersectN<kFast, 4>(pr.org, pr.dir, v, pr.tmin, tmax, t, vbool<4>(true));
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
