// One ray at a time through the N-wide BVH (BVH4_CPU / BVH8_CPU of
// simd/bvh_wide.h; Wald, Benthin & Boulos 2008, "Getting rid of packets",
// and Dammertz et al. 2008, "Shallow bounding volume hierarchies"): the ray
// tests all N child boxes of a node at once, visits the hit children nearest
// first (any-hit queries: in slot order; the others wait on the stack with
// their entry distance, their lines prefetched), and tests the primitives of
// a leaf K at a time from structure-of-arrays packs.
//
// Same answers as BVH_Trace: every box and primitive test is the scalar one
// lane by lane; a pack's hits are reduced with Hit_Closer's order (nearer t,
// then lower g, which is lane order inside a pack), so the closest hit does
// not depend on the visiting order, and a pending node is dropped only when
// its entry distance is beyond the current hit (as the scalar stack pop).
// Except where the two walks test different primitives (their leaves differ:
// packs of 8 merge more binary leaves, and the SIMD backend's SAH may count
// blocks, docs/ACCEL.md) and a ray grazes a vertex that a float test hits
// and exact arithmetic misses: there the answers differ within the ray's
// tolerance (tests/test_simd_cells.cpp, the frustum test).
// Statistics: nTS counts wide nodes and leaves visited, nIT the real
// primitives of every pack tested.
#pragma once

#include <cstddef>
#include <cstdint>

#include "simd/bvh_packet.h"
#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// Hit_CloserOn's order of two spheres whose float distances tie exactly
// (robust mode), for the ray of the pack: -1 when sphere ga comes first.
template <int K>
CR_SIMD_INLINE int Pack_SphereTieOrder(const KernelScene& sc, const PackRay<K>& pr, std::uint32_t ga,
                                       std::uint32_t gb)
{
  const float org[3] = {pr.org[0][0], pr.org[1][0], pr.org[2][0]};
  const float dir[3] = {pr.dir[0][0], pr.dir[1][0], pr.dir[2][0]};
  return Sphere_TieOrder(org, dir, pr.tmin[0], &ScenePrims<Sphere>(sc)[ga], &ScenePrims<Sphere>(sc)[gb]);
}
// The same on lane `lane` of a moving scene's pack ray, whose lanes each
// piece shifts apart (PackRay_Shift): the ray as sphere ga sees it, as
// Prim_Intersect asks Hit_CloserOn.
template <int K>
CR_SIMD_INLINE int Pack_SphereTieOrderAt(const KernelScene& sc, const PackRay<K>& pr, int lane, std::uint32_t ga,
                                         std::uint32_t gb)
{
  const float org[3] = {pr.org[0][lane], pr.org[1][lane], pr.org[2][lane]};
  const float dir[3] = {pr.dir[0][lane], pr.dir[1][lane], pr.dir[2][lane]};
  return Sphere_TieOrder(org, dir, pr.tmin[0], &ScenePrims<Sphere>(sc)[ga], &ScenePrims<Sphere>(sc)[gb]);
}

// Keeps the pack's best hit if it is closer (Hit_Closer); true when the hit
// changed. With `tieScene` set (a sphere pack in robust mode), ties between
// spheres follow Hit_CloserOn: double-float distance first, then id (kMotion:
// on tieRay's lane of the challenging sphere, Pack_SphereTieOrderAt).
template <int K, bool kMotion = false>
CR_SIMD_INLINE bool Pack_Reduce(vbool<K> ok, vfloat<K> t, vfloat<K> u, vfloat<K> v, const std::uint32_t* g, Hit& hit,
                                const KernelScene* tieScene = nullptr, const PackRay<K>* tieRay = nullptr)
{
  if (None(ok)) return false;
  const float best = HMin(Select(ok, t, vfloat<K>(__builtin_inff())));
  const unsigned tied = (ok & (t == vfloat<K>(best))).Bits();
  int lane = LowestBit(tied);
  // Several spheres at the same float t: the sequential loop's choice.
  if (tieScene)
    for (unsigned rest = tied & (tied - 1u); rest; rest &= rest - 1u) {
      const int l = LowestBit(rest);
      if constexpr (kMotion) {
        if (Pack_SphereTieOrderAt<K>(*tieScene, *tieRay, l, g[l], g[lane]) < 0) lane = l;
      } else {
        if (Pack_SphereTieOrder<K>(*tieScene, *tieRay, g[l], g[lane]) < 0) lane = l;
      }
    }
  const std::uint32_t gl = g[lane];
  bool closer;
  if (tieScene && best == hit.t && gl != hit.g && hit.g < Prim_End(&tieScene->ranges, CR_PRIM_SPHERE)) {
    int order;
    if constexpr (kMotion)
      order = Pack_SphereTieOrderAt<K>(*tieScene, *tieRay, lane, gl, hit.g);
    else
      order = Pack_SphereTieOrder<K>(*tieScene, *tieRay, gl, hit.g);
    closer = order != 0 ? order < 0 : gl < hit.g;
  } else {
    closer = Hit_Closer(best, gl, &hit);
  }
  if (!closer) return false;
  hit.t = best;
  hit.u = u[lane];
  hit.v = v[lane];
  hit.g = gl;
  return true;
}

template <int K>
CR_SIMD_INLINE vbool<K> Pack_Valid(const std::uint32_t* g)
{
  return !(vint<K>::Load(g) == vint<K>(static_cast<int>(CR_NO_HIT)));
}

// `count` packs of type T from `first` (SimdTest<T>::Pack). Returns true to
// stop (an occlusion query has its occluder); `changed` when the hit changed.
// kMotion (a moving scene): each lane's piece meets the ray shifted into its
// rest frame (PackRay_Shift).
template <class T, int K, bool kFast, bool kStats, bool kMotion>
CR_SIMD_INLINE bool WideLeaf_IntersectType(const KernelScene& sc, std::uint32_t first, int count, const PackRay<K>& pr,
                                           Hit& hit, int anyHit, TraceStatsSum& st, bool& changed)
{
  constexpr unsigned k = kPrimIndex<T>;
  using Pack = typename SimdPrim<T>::template Pack<K>;
  // Exact ties between two of the type's primitives ordered by distance
  // (spheres, robust mode: Hit_CloserOn).
  constexpr bool kTies = SimdPrim<T>::kDistanceTies && !kFast;
  const Pack* packs = static_cast<const Pack*>(sc.packs[k]) + first;
  for (int p = 0; p < count; ++p) {
    const Pack& pk = packs[p];
    const vbool<K> valid = Pack_Valid<K>(pk.g);
    if constexpr (kStats) st.nIT += PopCount(valid.Bits());
    vfloat<K> t, u(0.0f), v(0.0f);
    if constexpr (kMotion) {
      PackRay<K> shifted;
      const PackRay<K>& ray = PackRay_Shift<K>(sc, pk.g, valid, pr, shifted) ? shifted : pr;
      const vbool<K> ok = valid & SimdTest<T>::template Pack<K, kFast>(sc, pk, valid, ray, vfloat<K>(hit.t), t, u, v);
      if (Pack_Reduce<K, true>(ok, t, u, v, pk.g, hit, kTies ? &sc : nullptr, &ray)) {
        changed = true;
        if (anyHit) return true;
      }
      continue;
    }
    const vbool<K> ok = valid & SimdTest<T>::template Pack<K, kFast>(sc, pk, valid, pr, vfloat<K>(hit.t), t, u, v);
    if (Pack_Reduce<K>(ok, t, u, v, pk.g, hit, kTies ? &sc : nullptr, &pr)) {
      changed = true;
      if (anyHit) return true;
    }
  }
  return false;
}

// A leaf slot (simd/bvh_wide.h): `p` its child without the leaf flag, `meta`
// its meta word. Returns true when the hit changed (occlusion: as soon as it
// does).
template <int K, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE bool WideLeaf_Intersect(const KernelScene& sc, std::uint32_t p, std::uint32_t meta, const PackRay<K>& pr,
                                       Hit& hit, int anyHit, TraceStatsSum& st)
{
  bool changed = false;
  if (meta != kWideMixedLeaf) {
    // One type: its packs, straight from the slot.
    const std::uint32_t type = (meta >> 16) - 1u;
    const int count = static_cast<int>(meta & 0xffffu);
#define CR_SIMD_LEAF_RUN_(T, U, a)                                                                                 \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u)                                                                      \
    if (type == CR_PRIM_##U) {                                                                                     \
      WideLeaf_IntersectType<T, K, kFast, kStats, kHasMotion<kTypes>>(sc, p, count, pr, hit, anyHit, st, changed); \
      return changed;                                                                                              \
    }
    CR_PRIM_TYPES(CR_SIMD_LEAF_RUN_)
#undef CR_SIMD_LEAF_RUN_
    return false;
  }
  const WideLeaf& leaf = sc.wideLeaves[p];
#define CR_SIMD_LEAF_TYPE_(T, U, a)                                                                               \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u)                                                                     \
    if (WideLeaf_IntersectType<T, K, kFast, kStats, kHasMotion<kTypes>>(sc, leaf.first[CR_PRIM_##U],              \
                                                                        leaf.count[CR_PRIM_##U], pr, hit, anyHit, \
                                                                        st, changed))                             \
      return true;
  CR_PRIM_TYPES(CR_SIMD_LEAF_TYPE_)
#undef CR_SIMD_LEAF_TYPE_
  return changed;
}

// Asks the cache for the slot's data (a wide node, or a one-type leaf's
// first packs) ahead of its visit: a ray that enters several children walks
// the nearest first, while the others' lines arrive (incoherent rays miss
// the cache on nearly every node and leaf).
template <int N, int K, unsigned kTypes>
CR_SIMD_INLINE void WideSlot_Prefetch(const KernelScene& sc, const WideNode<N>* nodes, std::uint32_t ref,
                                      std::uint32_t meta)
{
  const char* a;
  int bytes;
  if (!(ref & kWideLeafFlag)) {
    a = reinterpret_cast<const char*>(nodes + ref);
    bytes = static_cast<int>(sizeof(WideNode<N>));
  } else {
    if (meta == kWideMixedLeaf) return;
    const std::uint32_t type = (meta >> 16) - 1u;
    const int packs = static_cast<int>(meta & 0xffffu) < 2 ? static_cast<int>(meta & 0xffffu) : 2;
    a = nullptr;
    bytes = 0;
#define CR_SIMD_LEAF_PREFETCH_(T, U, x)                                                             \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u)                                                       \
    if (type == CR_PRIM_##U) {                                                                      \
      using Pack = typename SimdPrim<T>::template Pack<K>;                                          \
      a = reinterpret_cast<const char*>(static_cast<const Pack*>(sc.packs[CR_PRIM_##U]) + (ref & ~kWideLeafFlag)); \
      bytes = packs * static_cast<int>(sizeof(Pack));                                               \
    }
    CR_PRIM_TYPES(CR_SIMD_LEAF_PREFETCH_)
#undef CR_SIMD_LEAF_PREFETCH_
  }
  // Each 64-byte line of [a, a + bytes) once (a node is line-aligned; a
  // pack need not be).
  const std::uintptr_t first = reinterpret_cast<std::uintptr_t>(a) & ~std::uintptr_t(63);
  const std::uintptr_t last = reinterpret_cast<std::uintptr_t>(a) + std::uintptr_t(bytes) - 1u;
  for (std::uintptr_t line = first; bytes && line <= last; line += 64)
    __builtin_prefetch(reinterpret_cast<const void*>(line));
}

// Closest hit (anyHit = 0) or any hit of one ray in the subtree of the slot
// (ref, meta) (the root: 0, 0); `hit` from Hit_Init or a closer hit so far.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void BVHSingle_TraceFrom(const KernelScene& sc, const Ray& ray, Hit& hit, int anyHit,
                                        TraceStatsSum& st, std::uint32_t ref, std::uint32_t meta)
{
  struct Entry {
    std::uint32_t ref, meta;
    float t;
  };
  // Each wide level pushes at most N - 1 entries; the wide depth is at most
  // the binary depth bound.
  Entry stack[(N - 1) * kBVHStack + 1];
  int sp = 0;
  // Closest hit: children nearest first. Any hit: in slot order (the
  // query ends at any occluder; sorting cost more than it found sooner).
  const bool sorted = !anyHit;
  const WideNode<N>* nodes = static_cast<const WideNode<N>*>(sc.wideNodes);
  vfloat<N> org[3], inv[3];
  // Byte offsets of the near and far planes of each axis in a node, chosen
  // once per ray (no per-node branch on the direction's signs).
  std::size_t nearOff[3], farOff[3];
  for (int a = 0; a < 3; ++a) {
    org[a] = vfloat<N>(ray.org[a]);
    inv[a] = vfloat<N>(ray.inv[a]);
    const bool hi = ray.inv[a] < 0.0f;
    nearOff[a] = (hi ? offsetof(WideNode<N>, upper) : offsetof(WideNode<N>, lower)) + a * N * sizeof(float);
    farOff[a] = (hi ? offsetof(WideNode<N>, lower) : offsetof(WideNode<N>, upper)) + a * N * sizeof(float);
  }
  const vfloat<N> tmin(ray.tmin);
  PackRayOf<K, kHasMotion<kTypes>> pr;
  PackRay_Init<K>(pr, ray);
  if constexpr (kHasMotion<kTypes>) pr.time = ray.time;
  pr.anyHit = anyHit != 0;
  for (;;) {
    if (!(ref & kWideLeafFlag)) {
      const WideNode<N>& n = nodes[ref];
      if constexpr (kStats) ++st.nTS;
      const float* nearP[3];
      const float* farP[3];
      const char* nb = reinterpret_cast<const char*>(&n);
      for (int a = 0; a < 3; ++a) {
        nearP[a] = reinterpret_cast<const float*>(nb + nearOff[a]);
        farP[a] = reinterpret_cast<const float*>(nb + farOff[a]);
      }
      vfloat<N> tE;
      unsigned bits = Box_IntersectBoxes<kFast, N>(nearP, farP, org, inv, tmin, vfloat<N>(CullDistance<kFast>(hit.t)), tE).Bits();
      if (bits) {
        const int i0 = LowestBit(bits);
        bits &= bits - 1;
        if (!bits) {
          ref = n.child[i0];
          meta = n.meta[i0];
          continue;
        }
        // Two or more: push all, farthest deepest, and continue with the
        // nearest; each asked of the cache now, while the nearest is walked.
        alignas(32) float te[N];
        tE.Store(te);
        const int base = sp;
        WideSlot_Prefetch<N, K, kTypes>(sc, nodes, n.child[i0], n.meta[i0]);
        stack[sp++] = {n.child[i0], n.meta[i0], te[i0]};
        do {
          const int i = LowestBit(bits);
          bits &= bits - 1;
          WideSlot_Prefetch<N, K, kTypes>(sc, nodes, n.child[i], n.meta[i]);
          int j = sp++;
          while (sorted && j > base && stack[j - 1].t < te[i]) {
            stack[j] = stack[j - 1];
            --j;
          }
          stack[j] = {n.child[i], n.meta[i], te[i]};
        } while (bits);
        --sp;
        ref = stack[sp].ref;
        meta = stack[sp].meta;
        continue;
      }
    } else {
      if constexpr (kStats) {
        ++st.nTS;
        ++st.nLeaves;
      }
      if (WideLeaf_Intersect<K, kTypes, kFast, kStats>(sc, ref & ~kWideLeafFlag, meta, pr, hit, anyHit, st) && anyHit)
        return;
    }
    for (;;) {
      if (sp == 0) return;
      --sp;
      if (stack[sp].t <= CullDistance<kFast>(hit.t)) {
        ref = stack[sp].ref;
        meta = stack[sp].meta;
        break;
      }
    }
  }
}

// Closest hit (anyHit = 0) or any hit of one ray; `hit` from Hit_Init.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void BVHSingle_Trace(const KernelScene& sc, const Ray& ray, Hit& hit, int anyHit, TraceStatsSum& st)
{
  BVHSingle_TraceFrom<N, K, kTypes, kFast, kStats>(sc, ray, hit, anyHit, st, 0u, 0u);
}

// The lanes of a packet as scalar rays: what Ray_Init makes of each record.
template <int N>
CR_SIMD_INLINE void RayPacket_Extract(const RayPacket<N>& P, const HitPacket<N>& H, Ray* rays)
{
  alignas(32) float org[3][N], dir[3][N], inv[3][N], s[3][N], tmin[N], tmax[N];
  alignas(32) std::uint32_t k[3][N];
  for (int a = 0; a < 3; ++a) {
    P.org[a].Store(org[a]);
    P.dir[a].Store(dir[a]);
    P.inv[a].Store(inv[a]);
    P.s[a].Store(s[a]);
    P.k[a].Store(k[a]);
  }
  P.tmin.Store(tmin);
  H.t.Store(tmax);
  for (int l = 0; l < N; ++l) {
    Ray& ray = rays[l];
    for (int a = 0; a < 3; ++a) {
      ray.org[a] = org[a][l];
      ray.dir[a] = dir[a][l];
      ray.inv[a] = inv[a][l];
    }
    ray.tmin = tmin[l];
    ray.tmax = tmax[l];
    ray.sx = s[0][l];
    ray.sy = s[1][l];
    ray.sz = s[2][l];
    ray.kx = static_cast<int>(k[0][l]);
    ray.ky = static_cast<int>(k[1][l]);
    ray.kz = static_cast<int>(k[2][l]);
  }
}

// The loop of the single-ray TraceRanges: positions [job.begin, job.end) one
// ray at a time, each traced by trace(ray, hit, anyHit, st). Rays are
// prepared N at a time by the packet's vectorised Ray_Init (RayPacket_Init),
// which has no data-dependent branches, unlike the scalar Ray_Init that an
// incoherent ray set would make mispredict on every ray. kMotion (a moving
// scene): each ray also takes its time (Ray::time).
template <int N, bool kStats, bool kMotion, class TraceFn>
CR_SIMD_INLINE void Single_TraceRangeWith(const KernelScene& sc, const KernelJob& job, TraceFn&& trace)
{
  const PrimView pv = MakePrimView(sc);
  TraceStatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = Job_Rays<N>(job, p, recs, idx);
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    Ray rays[N];
    RayPacket_Extract<N>(P, H, rays);
    for (int l = 0; l < count; ++l) {
      if constexpr (kMotion) rays[l].time = Job_Time(job, idx[l]);
      Hit hit;
      Hit_Init(&hit, &rays[l]);
      trace(rays[l], hit, job.occlusion, st);
      job.hits[idx[l]] = Hit_ToRecord(&hit, &pv, sc.primIds, job.occlusion, sc.unifiedHits);
    }
  }
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

// Traces positions [job.begin, job.end) one ray at a time.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
void BVHSingle_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Single_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](const Ray& ray, Hit& hit, int anyHit, TraceStatsSum& st) {
        BVHSingle_Trace<N, K, kTypes, kFast, kStats>(sc, ray, hit, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
