// The single-ray kernels of one ISA (every type set x precision x
// statistics) and the probes the unit tests call. Compiled once per ISA
// (simd/CMakeLists.txt), with the ISA namespace, CR_SIMD_WIDTH (N, children
// per node) and CR_SIMD_PACK_WIDTH (K, primitives per pack) of simd/vec.h.
#include "simd/bvh_packet.h"
#include "simd/bvh_single.h"

namespace cr::simd::CR_SIMD_NS {

namespace {

constexpr int N = CR_SIMD_WIDTH;
constexpr int K = CR_SIMD_PACK_WIDTH;

template <unsigned kTypes>
KernelFn PickSingle(bool fast, bool stats)
{
  if (fast)
    return stats ? &BVHSingle_TraceRange<N, K, kTypes, true, true> : &BVHSingle_TraceRange<N, K, kTypes, true, false>;
  return stats ? &BVHSingle_TraceRange<N, K, kTypes, false, true> : &BVHSingle_TraceRange<N, K, kTypes, false, false>;
}

// A ray prepared as the single-ray kernels prepare it (RayPacket_Init, then
// one lane); the scalar Ray_Init is not compiled into the ISA units.
Ray PreparedRay(const RayRecord& rec)
{
  const RayRecord* recs[N];
  for (int l = 0; l < N; ++l) recs[l] = &rec;
  RayPacket<N> P;
  HitPacket<N> H;
  RayPacket_Init<N>(P, H, recs);
  Ray rays[N];
  RayPacket_Extract<N>(P, H, rays);
  return rays[0];
}

// Probes: the intersectors on given inputs, lane by lane, for the tests.
template <bool kFast>
void ProbePacketPrimT(const KernelScene& sc, const RayRecord* rays, std::uint32_t g, ProbeResult* out)
{
  const RayRecord* recs[N];
  for (int l = 0; l < N; ++l) recs[l] = &rays[l];
  RayPacket<N> P;
  HitPacket<N> H;
  RayPacket_Init<N>(P, H, recs);
  const vbool<N> changed = PacketPrim_Intersect<N, 7, kFast>(sc, g, P, H, vbool<N>(true));
  const unsigned bits = changed.Bits();
  for (int l = 0; l < N; ++l) {
    out[l].hit = (bits >> l) & 1u;
    out[l].t = H.t[l];
    out[l].u = H.u[l];
    out[l].v = H.v[l];
  }
}

void ProbePacketPrim(const KernelScene& sc, const RayRecord* rays, std::uint32_t g, bool fast, ProbeResult* out)
{
  fast ? ProbePacketPrimT<true>(sc, rays, g, out) : ProbePacketPrimT<false>(sc, rays, g, out);
}

// One pack of the given primitives (all of one type), built here the way
// simd/bvh_wide_builder.cpp builds them.
template <bool kFast>
void ProbeSinglePrimsT(const KernelScene& sc, const RayRecord& rec, const std::uint32_t* gs, ProbeResult* out)
{
  const Ray ray = PreparedRay(rec);
  PackRay<K> pr;
  PackRay_Init<K>(pr, ray);
  const PrimRanges& c = sc.ranges;
  SpherePack<K> sp{};
  TrianglePack<K> tp{};
  ConePack<K> cp{};
  PrimType type = PrimType::Sphere;
  for (int l = 0; l < K; ++l) {
    const std::uint32_t g = gs[l];
    sp.g[l] = tp.g[l] = cp.g[l] = g;
    if (g == CR_NO_HIT) continue;
    type = TypeOf<7>(g, c);
    if (type == PrimType::Sphere) {
      for (int i = 0; i < 3; ++i) sp.center[i][l] = sc.spheres[g].center[i];
      sp.radius[l] = sc.spheres[g].radius;
    } else if (type == PrimType::Triangle) {
      const Triangle& t = sc.triangles[Prim_Local(&c, CR_PRIM_TRIANGLE, g)];
      for (int i = 0; i < 3; ++i) {
        tp.v[0][i][l] = t.v0[i];
        tp.v[1][i][l] = t.v1[i];
        tp.v[2][i][l] = t.v2[i];
      }
      tp.flags[l] = t.flags;
    } else {
      const ConeData& d = sc.cones[Prim_Local(&c, CR_PRIM_CONE, g)];
      for (int i = 0; i < 3; ++i) {
        cp.base[i][l] = d.base[i];
        cp.w[i][l] = d.w[i];
      }
      cp.H[l] = d.H;
      cp.r0[l] = d.r0;
      cp.k[l] = d.k;
    }
  }
  const vfloat<K> tmax(ray.tmax);
  vfloat<K> t(0.0f), u(0.0f), v(0.0f);
  vbool<K> ok;
  if (type == PrimType::Sphere) {
    vfloat<K> cen[3];
    for (int i = 0; i < 3; ++i) cen[i] = vfloat<K>::Load(sp.center[i]);
    ok = Sphere_IntersectN<kFast, K>(pr.org, cen, pr.dir, pr.dd, vfloat<K>::Load(sp.radius), pr.tmin, tmax, t);
  } else if (type == PrimType::Triangle) {
    if constexpr (kFast) {
      vfloat<K> v0[3], v1[3], v2[3];
      for (int i = 0; i < 3; ++i) {
        v0[i] = vfloat<K>::Load(tp.v[0][i]);
        v1[i] = vfloat<K>::Load(tp.v[1][i]);
        v2[i] = vfloat<K>::Load(tp.v[2][i]);
      }
      ok = Triangle_MollerTrumboreN<K>(v0, v1, v2, pr.org, pr.dir, pr.tmin, tmax, t, u, v);
    } else {
      vfloat<K> A[3], B[3], C[3];
      for (int j = 0; j < 3; ++j) {
        A[j] = vfloat<K>::Load(tp.v[0][pr.k[j]]) - pr.orgK[j];
        B[j] = vfloat<K>::Load(tp.v[1][pr.k[j]]) - pr.orgK[j];
        C[j] = vfloat<K>::Load(tp.v[2][pr.k[j]]) - pr.orgK[j];
      }
      ok = Triangle_WatertightN<K>(A, B, C, pr.s, PackPlane<K>{tp.v, tp.flags}, pr.org, pr.dir, pr.tmin, tmax, t, u, v);
    }
  } else {
    vfloat<K> dl[3], w[3];
    for (int i = 0; i < 3; ++i) {
      dl[i] = pr.org[i] - vfloat<K>::Load(cp.base[i]);
      w[i] = vfloat<K>::Load(cp.w[i]);
    }
    ok = Cone_IntersectN<kFast, K>(pr.org, dl, pr.dir, w, vfloat<K>::Load(cp.H), vfloat<K>::Load(cp.r0),
                                   vfloat<K>::Load(cp.k), pr.tmin, tmax, t, [&](int l) -> const Cone* {
                                     const std::uint32_t g = tp.g[l];
                                     return Pack_Valid<K>(tp.g).Bits() >> l & 1u
                                                ? &sc.coneGeometry[Prim_Local(&c, CR_PRIM_CONE, g)]
                                                : nullptr;
                                   });
  }
  ok = ok & Pack_Valid<K>(tp.g);
  const unsigned bits = ok.Bits();
  for (int l = 0; l < K; ++l) {
    out[l].hit = (bits >> l) & 1u;
    out[l].t = t[l];
    out[l].u = u[l];
    out[l].v = v[l];
  }
}

void ProbeSinglePrims(const KernelScene& sc, const RayRecord& ray, const std::uint32_t* gs, bool fast, ProbeResult* out)
{
  fast ? ProbeSinglePrimsT<true>(sc, ray, gs, out) : ProbeSinglePrimsT<false>(sc, ray, gs, out);
}

template <bool kFast>
void ProbePacketBoxT(const float lo[3], const float hi[3], const RayRecord* rays, ProbeResult* out)
{
  const RayRecord* recs[N];
  for (int l = 0; l < N; ++l) recs[l] = &rays[l];
  RayPacket<N> P;
  HitPacket<N> H;
  RayPacket_Init<N>(P, H, recs);
  BVHNode node{};
  for (int a = 0; a < 3; ++a) {
    node.bmin[a] = lo[a];
    node.bmax[a] = hi[a];
  }
  vfloat<N> tE;
  const unsigned bits = PacketBox_Intersect<N, kFast>(node, P, H.t, tE).Bits();
  for (int l = 0; l < N; ++l) {
    out[l].hit = (bits >> l) & 1u;
    out[l].t = tE[l];
  }
}

void ProbePacketBox(const float lo[3], const float hi[3], const RayRecord* rays, bool fast, ProbeResult* out)
{
  fast ? ProbePacketBoxT<true>(lo, hi, rays, out) : ProbePacketBoxT<false>(lo, hi, rays, out);
}

template <bool kFast>
void ProbeSingleBoxesT(const float* lo, const float* hi, const RayRecord& rec, ProbeResult* out)
{
  const Ray ray = PreparedRay(rec);
  vfloat<N> org[3], inv[3];
  const float* nearP[3];
  const float* farP[3];
  for (int a = 0; a < 3; ++a) {
    org[a] = vfloat<N>(ray.org[a]);
    inv[a] = vfloat<N>(ray.inv[a]);
    const bool neg = ray.inv[a] < 0.0f;
    nearP[a] = (neg ? hi : lo) + a * N;
    farP[a] = (neg ? lo : hi) + a * N;
  }
  vfloat<N> tE;
  const unsigned bits =
      Box_IntersectBoxes<kFast, N>(nearP, farP, org, inv, vfloat<N>(ray.tmin), vfloat<N>(ray.tmax), tE).Bits();
  for (int l = 0; l < N; ++l) {
    out[l].hit = (bits >> l) & 1u;
    out[l].t = tE[l];
  }
}

void ProbeSingleBoxes(const float* lo, const float* hi, const RayRecord& ray, bool fast, ProbeResult* out)
{
  fast ? ProbeSingleBoxesT<true>(lo, hi, ray, out) : ProbeSingleBoxesT<false>(lo, hi, ray, out);
}

}  // namespace

KernelFn SelectSingleKernel(const KernelKey& key)
{
  switch (key.types) {
    case 1: return PickSingle<1>(key.fast, key.stats);
    case 2: return PickSingle<2>(key.fast, key.stats);
    case 3: return PickSingle<3>(key.fast, key.stats);
    case 4: return PickSingle<4>(key.fast, key.stats);
    case 5: return PickSingle<5>(key.fast, key.stats);
    case 6: return PickSingle<6>(key.fast, key.stats);
    case 7: return PickSingle<7>(key.fast, key.stats);
  }
  return nullptr;
}

KernelProbes Probes()
{
  KernelProbes p;
  p.width = N;
  p.packWidth = K;
  p.packetPrim = &ProbePacketPrim;
  p.singlePrims = &ProbeSinglePrims;
  p.packetBox = &ProbePacketBox;
  p.singleBoxes = &ProbeSingleBoxes;
  return p;
}

}  // namespace cr::simd::CR_SIMD_NS
