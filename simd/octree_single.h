// Octree, one ray at a time, for incoherent rays: Octree_Trace of
// kernels/octree.h step by step (the same planes, parameters, child order and
// stopping rules), with SIMD inside the ray's work: rays are prepared N at a
// time (RayPacket_Init), and a leaf's primitives are tested 4 at a time,
// gathered from the scene arrays (simd/prim_range.h; no extra memory), those
// in the ray's mailbox skipped where the octree has one (--octree-mailbox).
// The stack keeps each ancestor's parameters instead of recomputing them from
// the planes on the way back up: they are the same values, bit for bit.
#pragma once

#include "simd/bvh_single.h"
#include "simd/kernel_common.h"
#include "simd/octree_packet.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// fmaxf / fminf of C where neither operand is NaN (glibc x86-64: maxss /
// minss, which return b on a tie, as the vector FMax / FMin). No parameter
// is NaN: Ray_PlaneT maps NaN to 0, and tmin and the hit distance are
// numbers.
CR_SIMD_INLINE float FMaxS(float a, float b) { return a > b ? a : b; }
CR_SIMD_INLINE float FMinS(float a, float b) { return a < b ? a : b; }

// The children of a node that Octree_TraceRay visits: mirrored child m
// (octant m ^ signMask) when it is stored and its interval, widened by
// OctreeLo and OctreeHi, meets [tmin, hitT]; its widened entry goes to
// enter[m]. Returns the mirrored children as bits.
template <int N>
CR_SIMD_INLINE std::uint32_t OctreeChildrenToVisit(std::uint32_t childMask, std::uint32_t signMask, const float t0[3],
                                                   const float tm[3], const float t1[3], float tmin, float hitT,
                                                   float enter[8])
{
  const std::uint32_t mine = OctreeMirroredChildren(childMask, signMask);
  const vfloat<N> lo(1.0f - kOctreeWiden), hi(1.0f + kOctreeWiden), tiny(0x1.0p-126f), zero(0.0f);
  std::uint32_t todo = 0u;
  for (int base = 0; base < 8; base += N) {
    const unsigned kAllLanes = (1u << N) - 1u;
    // Lanes whose child has the bit of axis a set: 0xAA, 0xCC, 0xF0 from base.
    const vbool<N> up[3] = {vbool<N>::FromBits((0xAAu >> base) & kAllLanes),
                            vbool<N>::FromBits((0xCCu >> base) & kAllLanes),
                            vbool<N>::FromBits((0xF0u >> base) & kAllLanes)};
    vfloat<N> ce, cx;
    for (int a = 0; a < 3; ++a) {
      const vfloat<N> e = Select(up[a], vfloat<N>(tm[a]), vfloat<N>(t0[a]));
      const vfloat<N> x = Select(up[a], vfloat<N>(t1[a]), vfloat<N>(tm[a]));
      ce = a == 0 ? e : Max(ce, e);
      cx = a == 0 ? x : Min(cx, x);
    }
    ce = ce * Select(ce > zero, lo, hi) - tiny;
    cx = cx * Select(cx > zero, hi, lo) + tiny;
    const vbool<N> meets = Max(ce, vfloat<N>(tmin)) <= Min(cx, vfloat<N>(hitT));
    ce.Store(enter + base);
    todo |= meets.Bits() << base;
  }
  return todo & mine;
}

// Octree_TraceRay of kernels/octree.h (--octree-margin ray): the search of
// the tree, front to back, with each cell's interval widened by the ray's
// own rounding; the same parameters, children, order and counts. A leaf is
// tested as in the classic walk (`leaf`, which never ends the search by
// itself but for an any-hit query's hit).
template <int N, unsigned kTypes, bool kFast, bool kStats, typename Leaf>
CR_SIMD_INLINE void OctreeSingle_TraceRay(const KernelScene& sc, const Ray& ray, Hit& hit, std::uint32_t signMask,
                                          const float rootT[9], TraceStatsSum& st, Leaf&& leaf)
{
  const OctreeHeader& hdr = *sc.octreeHeader;
  const OctreeNode* nodes = sc.octreeNodes;
  struct Frame {
    float t[9];  // the node's mirrored t0, tm, t1
    float enter[8];
    std::uint32_t node, todo;
  };
  Frame stack[kOctreeMaxDepth];
  std::uint32_t c[3] = {0u, 0u, 0u};
  float t0[3], tm[3], t1[3];
  for (int a = 0; a < 3; ++a) {
    t0[a] = rootT[a];
    tm[a] = rootT[3 + a];
    t1[a] = rootT[6 + a];
  }
  int level = 0;
  std::uint32_t ni = 0u;
  for (;;) {
    {
      // The eight children's widened intervals, N at a time (lane k is
      // mirrored child base + k), without a branch per child.
      Frame& f = stack[level];
      const std::uint32_t todo = OctreeChildrenToVisit<N>(nodes[ni].childMask, signMask, t0, tm, t1, ray.tmin,
                                                          hit.t, f.enter);
      for (int a = 0; a < 3; ++a) {
        f.t[a] = t0[a];
        f.t[3 + a] = tm[a];
        f.t[6 + a] = t1[a];
      }
      f.node = ni;
      f.todo = todo;
    }
    for (;;) {
      Frame& f = stack[level];
      if (f.todo == 0u) {
        if (level == 0) return;
        --level;
        for (std::uint32_t& ck : c) ck >>= 1;
        continue;
      }
      const std::uint32_t m = static_cast<std::uint32_t>(LowestBit(f.todo));
      f.todo &= f.todo - 1u;
      if (f.enter[m] > hit.t) continue;
      const std::uint32_t o = m ^ signMask;
      const OctreeNode& n = nodes[f.node];
      const std::uint32_t ci = n.first + PopCount(n.childMask & ((1u << o) - 1u));
      if constexpr (kStats) ++st.nTS;
      if (nodes[ci].childMask == 0u) {
        if (leaf(nodes[ci], -INFINITY)) return;
        continue;
      }
      for (int a = 0; a < 3; ++a) {
        const bool up = (m >> a) & 1u;
        t0[a] = up ? f.t[3 + a] : f.t[a];
        t1[a] = up ? f.t[6 + a] : f.t[3 + a];
        c[a] = 2u * c[a] + ((o >> a) & 1u);
      }
      ++level;
      for (int a = 0; a < 3; ++a)
        tm[a] = PlaneT(OctreePlane(hdr, a, static_cast<std::uint32_t>(level) + 1u, 2u * c[a] + 1u), ray.org[a],
                       ray.inv[a]);
      ni = ci;
      break;
    }
  }
}

// Closest hit (anyHit = 0) or any hit of one ray; `hit` from Hit_Init.
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void OctreeSingle_Trace(const KernelScene& sc, const Ray& ray, Hit& hit, int anyHit, TraceStatsSum& st)
{
  const OctreeHeader& hdr = *sc.octreeHeader;
  const bool rayMargin = (hdr.flags & CR_OCTREE_MARGIN_RAY) != 0u;
  const OctreeNode* nodes = sc.octreeNodes;
  std::uint32_t signMask = 0u;
  for (int a = 0; a < 3; ++a)
    if (ray.inv[a] < 0.0f) signMask |= 1u << a;
  struct Frame {
    float t0[3], tm[3], t1[3];
    std::uint32_t node, m;
  };
  Frame stack[kOctreeMaxDepth];
  int sp = 0;
  std::uint32_t c[3] = {0u, 0u, 0u};
  std::uint32_t level = 0u;
  float t0[3], tm[3], t1[3];
  for (int a = 0; a < 3; ++a) {
    const float lo = PlaneT(OctreePlane(hdr, a, 0u, 0u), ray.org[a], ray.inv[a]);
    const float hi = PlaneT(OctreePlane(hdr, a, 0u, 1u), ray.org[a], ray.inv[a]);
    tm[a] = PlaneT(OctreePlane(hdr, a, 1u, 1u), ray.org[a], ray.inv[a]);
    const bool neg = (signMask >> a) & 1u;
    t0[a] = neg ? hi : lo;
    t1[a] = neg ? lo : hi;
  }
  float rootEnter = FMaxS(FMaxS(t0[0], t0[1]), t0[2]);
  float rootExit = FMinS(FMinS(t1[0], t1[1]), t1[2]);
  if (rayMargin) {
    rootEnter = OctreeLo(rootEnter);
    rootExit = OctreeHi(rootExit);
  }
  if (!(FMaxS(rootEnter, ray.tmin) <= FMinS(rootExit, hit.t))) return;
  if constexpr (kStats) ++st.nTS;
  PackRayOf<4, kHasMotion<kTypes>> pr;
  PackRay_Init<4>(pr, ray);
  if constexpr (kHasMotion<kTypes>) pr.time = ray.time;
  pr.anyHit = anyHit != 0;
  // The mailbox (--octree-mailbox on; kernels/octree.h).
  const bool useMailbox = (hdr.flags & CR_OCTREE_MAILBOX_ON) != 0u;
  const bool leafBoxes = (hdr.flags & CR_OCTREE_LEAF_BOXES) != 0u;
  std::uint32_t mailbox[CR_OCTREE_MAILBOX];
  if (useMailbox)
    for (std::uint32_t& k : mailbox) k = CR_NO_HIT;
  // Octree_Leaf: true when the query is answered.
  auto leaf = [&](const OctreeNode& n, float tExit) {
    if constexpr (kStats) {
      ++st.nLeaves;
      if (n.count == 0u) ++st.nEmptyLeaves;
    }
    if (leafBoxes && n.count && !OctreeLeafBox_Hit<kFast>(sc, n, ray, hit.t)) return hit.t <= tExit;
    const std::uint32_t begin = n.first, end = n.first + n.count;
    if (useMailbox ? MailboxRefs_Intersect<CR_OCTREE_MAILBOX, kTypes, kFast, kStats>(sc, sc.octreeRefs, begin, end,
                                                                                     mailbox, 1, pr, hit, anyHit, st)
                   : RayRefs_Intersect<kTypes, kFast, kStats>(sc, sc.octreeRefs, begin, end, pr, hit, anyHit, st) &&
                         anyHit)
      return true;
    return hit.t <= tExit;
  };
  if (nodes[0].childMask == 0u) {
    leaf(nodes[0], rayMargin ? -INFINITY : rootExit);
    return;
  }
  if (rayMargin) {
    const float rootT[9] = {t0[0], t0[1], t0[2], tm[0], tm[1], tm[2], t1[0], t1[1], t1[2]};
    OctreeSingle_TraceRay<CR_SIMD_WIDTH, kTypes, kFast, kStats>(sc, ray, hit, signMask, rootT, st, leaf);
    return;
  }
  std::uint32_t ni = 0u;
  std::uint32_t m = (tm[0] < FMaxS(rootEnter, ray.tmin) ? 1u : 0u) | (tm[1] < FMaxS(rootEnter, ray.tmin) ? 2u : 0u) |
                    (tm[2] < FMaxS(rootEnter, ray.tmin) ? 4u : 0u);
  for (;;) {
    const float ce = FMaxS(FMaxS((m & 1u) ? tm[0] : t0[0], (m & 2u) ? tm[1] : t0[1]), (m & 4u) ? tm[2] : t0[2]);
    const float cx = FMinS(FMinS((m & 1u) ? t1[0] : tm[0], (m & 2u) ? t1[1] : tm[1]), (m & 4u) ? t1[2] : tm[2]);
    if (ce > hit.t) return;
    if (ce <= cx && cx >= ray.tmin) {
      const std::uint32_t o = m ^ signMask;
      const OctreeNode& n = nodes[ni];
      if constexpr (kStats) ++st.nTS;
      if (((n.childMask >> o) & 1u) == 0u) {
        if constexpr (kStats) {
          ++st.nLeaves;
          ++st.nEmptyLeaves;
        }
        if (hit.t <= cx) return;
      } else {
        const std::uint32_t ci = n.first + PopCount(n.childMask & ((1u << o) - 1u));
        if (nodes[ci].childMask == 0u) {
          if (leaf(nodes[ci], cx)) return;
        } else {
          Frame& f = stack[sp++];
          for (int a = 0; a < 3; ++a) {
            f.t0[a] = t0[a];
            f.tm[a] = tm[a];
            f.t1[a] = t1[a];
          }
          f.node = ni;
          f.m = m;
          ++level;
          for (int a = 0; a < 3; ++a) {
            c[a] = 2u * c[a] + ((o >> a) & 1u);
            if ((m >> a) & 1u)
              t0[a] = tm[a];
            else
              t1[a] = tm[a];
            tm[a] = PlaneT(OctreePlane(hdr, a, level + 1u, 2u * c[a] + 1u), ray.org[a], ray.inv[a]);
          }
          ni = ci;
          const float tStart = FMaxS(ce, ray.tmin);
          m = (tm[0] < tStart ? 1u : 0u) | (tm[1] < tStart ? 2u : 0u) | (tm[2] < tStart ? 4u : 0u);
          continue;
        }
      }
    }
    // Next child across the exit plane of child m, climbing while that is
    // the node's own far plane.
    for (;;) {
      const float fx = (m & 1u) ? t1[0] : tm[0];
      const float fy = (m & 2u) ? t1[1] : tm[1];
      const float fz = (m & 4u) ? t1[2] : tm[2];
      const std::uint32_t bit = (fx <= fy) ? (fx <= fz ? 1u : 4u) : (fy <= fz ? 2u : 4u);
      if ((m & bit) == 0u) {
        m |= bit;
        break;
      }
      if (sp == 0) return;
      const Frame& f = stack[--sp];
      for (int a = 0; a < 3; ++a) {
        t0[a] = f.t0[a];
        tm[a] = f.tm[a];
        t1[a] = f.t1[a];
        c[a] >>= 1;
      }
      ni = f.node;
      m = f.m;
      --level;
    }
  }
}

// Traces positions [job.begin, job.end) one ray at a time.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void OctreeSingle_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Single_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](const Ray& ray, Hit& hit, int anyHit, TraceStatsSum& st) {
        OctreeSingle_Trace<kTypes, kFast, kStats>(sc, ray, hit, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
