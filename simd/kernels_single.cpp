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
  const vbool<N> changed = PacketPrim_Intersect<N, kAllTypes, kFast>(sc, g, P, H, vbool<N>(true));
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

// One pack of the given primitives (all of type T), filled here the way
// simd/bvh_wide_builder.cpp fills them, against the ray.
template <class T, bool kFast>
vbool<K> ProbePack(const KernelScene& sc, const PackRay<K>& pr, const std::uint32_t* gs, vfloat<K> tmax, vfloat<K>& t,
                   vfloat<K>& u, vfloat<K>& v)
{
  typename SimdPrim<T>::template Pack<K> pack{};
  for (int l = 0; l < K; ++l) {
    pack.g[l] = gs[l];
    if (gs[l] != CR_NO_HIT)
      SimdPrim<T>::template Fill<K>(pack, l, PrimData<T>(sc)[Prim_Local(&sc.ranges, kPrimIndex<T>, gs[l])]);
  }
  const vbool<K> valid = Pack_Valid<K>(pack.g);
  return SimdTest<T>::template Pack<K, kFast>(sc, pack, valid, pr, tmax, t, u, v) & valid;
}

template <bool kFast>
void ProbeSinglePrimsT(const KernelScene& sc, const RayRecord& rec, const std::uint32_t* gs, ProbeResult* out)
{
  const Ray ray = PreparedRay(rec);
  PackRay<K> pr;
  PackRay_Init<K>(pr, ray);
  std::uint32_t any = CR_NO_HIT;
  for (int l = 0; l < K; ++l)
    if (gs[l] != CR_NO_HIT) any = gs[l];
  const vfloat<K> tmax(ray.tmax);
  vfloat<K> t(0.0f), u(0.0f), v(0.0f);
  vbool<K> ok(false);
#define CR_SIMD_PROBE_TYPE_(T, U, a) \
  if (Prim_Is(&sc.ranges, CR_PRIM_##U, any)) ok = ProbePack<T, kFast>(sc, pr, gs, tmax, t, u, v);
  CR_PRIM_TYPES(CR_SIMD_PROBE_TYPE_)
#undef CR_SIMD_PROBE_TYPE_
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
  return SelectKernel(key, [](auto types, auto flags) -> KernelFn {
    return &BVHSingle_TraceRange<N, K, decltype(types)::kValue, decltype(flags)::kFastValue, decltype(flags)::kStatsValue>;
  });
}

KernelFn SelectBVHKernel(const KernelKey& key) { return key.packet ? SelectPacketKernel(key) : SelectSingleKernel(key); }
// Coherent sets only take packets (the pilot decides the rest).
PacketOrder BVHPacketOrder() { return PacketOrder::Input; }

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
