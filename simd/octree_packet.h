// Octree, N rays at once: the Revelles-style parametric traversal of
// kernels/octree.h (Revelles, Urena & Lastra 2000) with one shared stack of
// nodes and per-lane parameters.
//
// Lanes are traversed together when their directions have the same signs
// (the same mirroring): a packet with mixed signs is traced once per sign
// class. Within a class every lane's walk through a node's children is a
// chain of mirrored octants m that only grows (each step sets one bit of
// m), so visiting the children in increasing m, each with the lanes whose
// current child it is, gives every lane exactly its scalar sequence of
// children. A child is entered when any of those lanes' intervals in it is
// non-empty; a lane then follows Octree_Trace step by step:
//  - its near, mid and far parameters come from Octree_Plane through
//    Ray_PlaneT (shared node coordinates, per-lane rays), its first child
//    from Octree_FirstChild, its next child from its smallest far parameter;
//  - it stops at a child whose entry lies beyond its current hit, after a
//    leaf or empty octant whose exit lies at or beyond the hit, or at its
//    first hit (occlusion).
// So hits, the order of primitive tests and the statistics (counted per
// lane) are the scalar backend's; with the octree's mailbox (--octree-mailbox
// on) each lane keeps its own, as Octree_Trace does.
#pragma once

#include <bit>

#include "simd/bvh_packet.h"
#include "simd/kernel_common.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// Deepest octree level (CR_OCTREE_MAX_DEPTH of kernels/octree.h): interior
// nodes lie above it, so it bounds both traversal stacks.
inline constexpr int kOctreeMaxDepth = 20;

// Octree_Plane of kernels/octree.h: rootMin + i * (rootSize * 2^-level), in float.
CR_SIMD_INLINE float OctreePlane(const OctreeHeader& h, int axis, std::uint32_t level, std::uint32_t i)
{
  const float cell = h.rootSize * __builtin_bit_cast(float, (127u - level) << 23);
  return h.rootMin[axis] + static_cast<float>(i) * cell;
}

// Octree_Lo and Octree_Hi of kernels/octree.h (--octree-margin ray): a
// float parameter moved outward by the ray's own rounding.
inline constexpr float kOctreeWiden = 0x1.0p-20f;
CR_SIMD_INLINE float OctreeLo(float t)
{
  return t * (t > 0.0f ? 1.0f - kOctreeWiden : 1.0f + kOctreeWiden) - 0x1.0p-126f;
}
CR_SIMD_INLINE float OctreeHi(float t)
{
  return t * (t > 0.0f ? 1.0f + kOctreeWiden : 1.0f - kOctreeWiden) + 0x1.0p-126f;
}

// The stored children in mirrored order: bit m is bit m ^ signMask of
// childMask (bits, pairs, nibbles swapped as signMask says).
CR_SIMD_INLINE std::uint32_t OctreeMirroredChildren(std::uint32_t childMask, std::uint32_t signMask)
{
  std::uint32_t mine = childMask;
  if (signMask & 1u) mine = ((mine & 0x55u) << 1) | ((mine & 0xAAu) >> 1);
  if (signMask & 2u) mine = ((mine & 0x33u) << 2) | ((mine & 0xCCu) >> 2);
  if (signMask & 4u) mine = ((mine & 0x0Fu) << 4) | ((mine & 0xF0u) >> 4);
  return mine;
}

template <int N>
CR_SIMD_INLINE vfloat<N> OctreeLoN(vfloat<N> t)
{
  return t * Select(t > vfloat<N>(0.0f), vfloat<N>(1.0f - kOctreeWiden), vfloat<N>(1.0f + kOctreeWiden)) -
         vfloat<N>(0x1.0p-126f);
}
template <int N>
CR_SIMD_INLINE vfloat<N> OctreeHiN(vfloat<N> t)
{
  return t * Select(t > vfloat<N>(0.0f), vfloat<N>(1.0f + kOctreeWiden), vfloat<N>(1.0f - kOctreeWiden)) +
         vfloat<N>(0x1.0p-126f);
}

// The state of one node on the packet's path.
template <int N>
struct OctreeFrame {
  vfloat<N> t0[3], tm[3], t1[3];  // each lane's mirrored near, mid and far parameters
  vint<N> cur;                    // each lane's current child (mirrored octant)
  std::uint32_t node;
  unsigned in;    // lanes still inside the node
  unsigned desc;  // lanes that descended into child m
  int m;          // the child being visited
};

// Octree_FirstChild per lane.
template <int N>
CR_SIMD_INLINE vint<N> OctreeFirstChildN(const vfloat<N> tm[3], vfloat<N> tStart)
{
  const vint<N> zero(0);
  return Select(tm[0] < tStart, vint<N>(1), zero) + Select(tm[1] < tStart, vint<N>(2), zero) +
         Select(tm[2] < tStart, vint<N>(4), zero);
}

// Moves the lanes of `lanes`, at child F.m, to their next child across the
// exit plane of their smallest far parameter; a lane whose exit plane is the
// node's own far plane leaves the node.
template <int N>
CR_SIMD_INLINE void OctreeFrame_Advance(OctreeFrame<N>& F, unsigned lanes)
{
  if (!lanes) return;
  const int m = F.m;
  const vfloat<N> fx = (m & 1) ? F.t1[0] : F.tm[0];
  const vfloat<N> fy = (m & 2) ? F.t1[1] : F.tm[1];
  const vfloat<N> fz = (m & 4) ? F.t1[2] : F.tm[2];
  const vbool<N> bx = (fx <= fy) & (fx <= fz);
  const vbool<N> by = AndNot(fy <= fz, fx <= fy);
  const vbool<N> bz = !(bx | by);
  const vint<N> bit = Select(bx, vint<N>(1), Select(by, vint<N>(2), vint<N>(4)));
  vbool<N> leaves(false);
  if (m & 1) leaves = leaves | bx;
  if (m & 2) leaves = leaves | by;
  if (m & 4) leaves = leaves | bz;
  const unsigned out = lanes & leaves.Bits();
  F.in &= ~out;
  const vbool<N> move = vbool<N>::FromBits(lanes & ~out);
  F.cur = Select(move, vint<N>(m) + bit, F.cur);
}

// A leaf's box (CR_OCTREE_LEAF_BOXES: the six float words before its
// references, kernels/types.h).
CR_SIMD_INLINE void OctreeLeafBox(const KernelScene& sc, const OctreeNode& n, float box[6])
{
  for (std::uint32_t i = 0; i < CR_OCTREE_BOX_WORDS; ++i)
    box[i] = std::bit_cast<float>(sc.octreeRefs[n.first - CR_OCTREE_BOX_WORDS + i]);
}
// Octree_LeafBoxHit for one ray: Box_Slabs' operations in its order.
template <bool kFast>
CR_SIMD_INLINE bool OctreeLeafBox_Hit(const KernelScene& sc, const OctreeNode& n, const Ray& ray, float hitT)
{
  float box[6];
  OctreeLeafBox(sc, n, box);
  float tEnter;
  return Box_SlabsOne<kFast>(box, box + 3, ray, ray.tmin, hitT, tEnter);
}

// Octree_Leaf for the lanes of `lanes`: tests the references, and returns
// the lanes whose query is answered (an occluder, or a closest hit so far at
// or before the leaf's exit cx).
// With `mailbox` (the octree has one: --octree-mailbox on), each lane
// skips the references in its own (slot k of lane l at mailbox[k][l]).
// Not inlined: its reference passes hold every primitive type's test, and
// both walks call it from two places each (compile time; a call per leaf is
// nothing beside the leaf's tests).
template <int N, unsigned kTypes, bool kFast, bool kStats>
__attribute__((noinline)) unsigned OctreePacket_Leaf(const KernelScene& sc, const OctreeNode& n, const RayPacket<N>& P,
                                          HitPacket<N>& H, unsigned lanes, vfloat<N> cx, int anyHit,
                                          std::uint32_t (*mailbox)[N], TraceStatsSum& st)
{
  if constexpr (kStats) {
    st.nLeaves += PopCount(lanes);
    if (n.count == 0u) st.nEmptyLeaves += PopCount(lanes);
  }
  unsigned done = 0;
  // The lanes that test the references: with leaf boxes, those entering it.
  unsigned test = n.count ? lanes : 0u;
  if (test && (sc.octreeHeader->flags & CR_OCTREE_LEAF_BOXES)) {
    float box[6];
    OctreeLeafBox(sc, n, box);
    vfloat<N> tEnter;
    test &= Box_IntersectRays<kFast, N>(box, box + 3, P.org, P.inv, P.invNeg, P.tmin, CullDistance<kFast, N>(H.t),
                                        tEnter)
                .Bits();
  }
  if (test) {
    const std::uint32_t begin = n.first, end = n.first + n.count;
    if (mailbox)
      MailboxPacketRefs_Intersect<N, CR_OCTREE_MAILBOX, kTypes, kFast, kStats>(
          sc, sc.octreeRefs, begin, end, mailbox, P, H, vbool<N>::FromBits(test), anyHit, done, st,
          [&](int l) { return PackRay_OfLane<N, kHasMotion<kTypes>>(P, l, anyHit); });
    else
      CellRefs_Intersect<N, kTypes, kFast, kStats>(sc, sc.octreeRefs, begin, end, P, H, vbool<N>::FromBits(test),
                                                   anyHit, done, st);
  }
  return done | (lanes & (H.t <= cx).Bits());
}

// Each lane's mirrored near, mid and far parameters of the root cell
// (Octree_CellT at level 0).
template <int N>
CR_SIMD_INLINE void OctreePacket_RootT(const OctreeHeader& hdr, const RayPacket<N>& P, unsigned signMask,
                                       vfloat<N> t0[3], vfloat<N> tm[3], vfloat<N> t1[3])
{
  for (int a = 0; a < 3; ++a) {
    const vfloat<N> lo = PlaneTN<N>(vfloat<N>(OctreePlane(hdr, a, 0u, 0u)), P.org[a], P.inv[a]);
    const vfloat<N> hi = PlaneTN<N>(vfloat<N>(OctreePlane(hdr, a, 0u, 1u)), P.org[a], P.inv[a]);
    tm[a] = PlaneTN<N>(vfloat<N>(OctreePlane(hdr, a, 1u, 1u)), P.org[a], P.inv[a]);
    const bool neg = (signMask >> a) & 1u;
    t0[a] = neg ? hi : lo;
    t1[a] = neg ? lo : hi;
  }
}

// The lanes of `lanes`, whose directions all have the sign bits signMask.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void OctreePacket_TraceSigns(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H,
                                            unsigned lanes, unsigned signMask, int anyHit,
                                            std::uint32_t (*mailbox)[N], TraceStatsSum& st)
{
  const OctreeHeader& hdr = *sc.octreeHeader;
  const OctreeNode* nodes = sc.octreeNodes;
  OctreeFrame<N> fr[kOctreeMaxDepth + 1];
  int d = 0;
  std::uint32_t c[3] = {0u, 0u, 0u};
  std::uint32_t level = 0u;
  OctreeFrame<N>* F = &fr[0];
  OctreePacket_RootT<N>(hdr, P, signMask, F->t0, F->tm, F->t1);
  const vfloat<N> rootEnter = FMax(FMax(F->t0[0], F->t0[1]), F->t0[2]);
  const vfloat<N> rootExit = FMin(FMin(F->t1[0], F->t1[1]), F->t1[2]);
  unsigned live = lanes & (FMax(rootEnter, P.tmin) <= FMin(rootExit, H.t)).Bits();
  if (!live) return;
  if constexpr (kStats) st.nTS += PopCount(live);
  if (nodes[0].childMask == 0u) {
    OctreePacket_Leaf<N, kTypes, kFast, kStats>(sc, nodes[0], P, H, live, rootExit, anyHit, mailbox, st);
    return;
  }
  F->cur = OctreeFirstChildN<N>(F->tm, FMax(rootEnter, P.tmin));
  F->node = 0u;
  F->in = live;
  F->desc = 0u;
  F->m = 0;
  for (;;) {
    // The next child that is some live lane's current one.
    unsigned here = 0;
    while (F->m < 8 && !(here = F->in & live & (F->cur == vint<N>(F->m)).Bits())) ++F->m;
    if (F->m == 8) {
      // Every lane has left the node: climb, and move the lanes that come
      // back from child m on in the parent.
      if (d == 0) return;
      F = &fr[--d];
      --level;
      for (int a = 0; a < 3; ++a) c[a] >>= 1;
      OctreeFrame_Advance<N>(*F, F->desc & live);
      ++F->m;
      continue;
    }
    const int m = F->m;
    // Child m spans [ce, cx] for each lane.
    const vfloat<N> ce =
        FMax(FMax((m & 1) ? F->tm[0] : F->t0[0], (m & 2) ? F->tm[1] : F->t0[1]), (m & 4) ? F->tm[2] : F->t0[2]);
    const vfloat<N> cx =
        FMin(FMin((m & 1) ? F->t1[0] : F->tm[0], (m & 2) ? F->t1[1] : F->tm[1]), (m & 4) ? F->t1[2] : F->tm[2]);
    // Front to back: a lane whose child starts beyond its hit is finished.
    const unsigned beyond = here & (ce > H.t).Bits();
    live &= ~beyond;
    here &= ~beyond;
    const unsigned vis = here & ((ce <= cx) & (cx >= P.tmin)).Bits();
    if (vis) {
      const std::uint32_t o = std::uint32_t(m) ^ signMask;
      const OctreeNode& n = nodes[F->node];
      if constexpr (kStats) st.nTS += PopCount(vis);
      if (((n.childMask >> o) & 1u) == 0u) {
        // An empty octant: an empty leaf that is not stored.
        if constexpr (kStats) {
          st.nLeaves += PopCount(vis);
          st.nEmptyLeaves += PopCount(vis);
        }
        live &= ~(vis & (H.t <= cx).Bits());
      } else {
        const std::uint32_t ci = n.first + PopCount(n.childMask & ((1u << o) - 1u));
        if (nodes[ci].childMask == 0u) {
          live &= ~OctreePacket_Leaf<N, kTypes, kFast, kStats>(sc, nodes[ci], P, H, vis, cx, anyHit, mailbox, st);
        } else {
          // Descend with the lanes that enter; the others move on first.
          OctreeFrame_Advance<N>(*F, here & ~vis);
          F->desc = vis;
          OctreeFrame<N>* G = &fr[++d];
          ++level;
          for (int a = 0; a < 3; ++a) {
            c[a] = 2u * c[a] + ((o >> a) & 1u);
            if ((m >> a) & 1) {
              G->t0[a] = F->tm[a];
              G->t1[a] = F->t1[a];
            } else {
              G->t0[a] = F->t0[a];
              G->t1[a] = F->tm[a];
            }
            G->tm[a] = PlaneTN<N>(vfloat<N>(OctreePlane(hdr, a, level + 1u, 2u * c[a] + 1u)), P.org[a], P.inv[a]);
          }
          G->cur = OctreeFirstChildN<N>(G->tm, FMax(ce, P.tmin));
          G->node = ci;
          G->in = vis;
          G->desc = 0u;
          G->m = 0;
          F = G;
          continue;
        }
      }
    }
    OctreeFrame_Advance<N>(*F, here & live);
    ++F->m;
  }
}

// The lazy search (OctreePacket_SearchSigns, kLazy; for the octrees whose
// heaviest path has a chain of kOctreeLazyChain levels, simd/simd_kernels.h)
// at the nodes that at least this many lanes enter.
inline constexpr int kOctreeLazyLanes = 4;

// Octree_TraceRay (--octree-margin ray) for the lanes of `lanes`, whose
// directions all have the sign bits signMask: one shared path through the
// tree; at each node, every lane's widened interval of each child (from its
// own parameters), and the children in increasing mirrored octant, each
// with the lanes whose interval met [tmin, hit t] when the node was entered
// and whose hit does not yet lie before its entry. Lane by lane that is the
// single walk's search (the same children, order and tests), so answers
// and counts are the scalar backend's.
//
// kLazy: a node's children after the first that some lane meets are met
// only when the walk comes back to the node, and not at all where every
// lane's hit by then lies before the least entry they can have. The same
// visits, order and counts (below). A packet that descends a chain of nodes
// to the detail it hits (the teapot in a stadium, seen from inside the
// stadium) then meets one child per level instead of four, and climbs back
// without meeting the others; a shadow ray climbs no higher than the node
// that holds its light. Elsewhere the bookkeeping costs more than it saves
// (primary and shadow rays of the SPD scenes and meshes 2-12% slower), so
// the tracer picks it by the tree's shape (kOctreeLazyChain).
template <int N, unsigned kTypes, bool kFast, bool kStats, bool kLazy>
CR_SIMD_INLINE void OctreePacket_SearchSigns(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H,
                                             unsigned lanes, unsigned signMask, int anyHit,
                                             std::uint32_t (*mailbox)[N], TraceStatsSum& st)
{
  const OctreeHeader& hdr = *sc.octreeHeader;
  const OctreeNode* nodes = sc.octreeNodes;
  // Each node's parameters are kept widened (OctreeLoN of its near and mid
  // parameters, OctreeHiN of its mid and far ones): the widening is monotone,
  // so a child's widened entry, the largest of its near parameters, is the
  // largest of their widened values, bit for bit, and a child inherits three
  // of its four widened triples from its parent.
  struct Frame {
    vfloat<N> e[2][3];  // OctreeLoN of the near ([0]) and mid ([1]) parameters, per axis
    vfloat<N> x[2][3];  // OctreeHiN of the mid ([0]) and far ([1]) parameters
    std::uint32_t node;
    unsigned todo;        // mirrored children still to visit, in increasing order
    unsigned deferred;    // stored mirrored children after the first met one, not yet met (below)
    unsigned lanes;       // the lanes that entered the node
    unsigned first;       // the first mirrored child met
    std::uint8_t in[8];   // per mirrored child: the lanes that met it on entry
  };
  Frame fr[kOctreeMaxDepth];
  std::uint32_t c[3] = {0u, 0u, 0u};
  int d = 0;
  Frame* F = &fr[0];
  {
    vfloat<N> t0[3], tm[3], t1[3];
    OctreePacket_RootT<N>(hdr, P, signMask, t0, tm, t1);
    for (int a = 0; a < 3; ++a) {
      F->e[0][a] = OctreeLoN<N>(t0[a]);
      F->e[1][a] = OctreeLoN<N>(tm[a]);
      F->x[0][a] = OctreeHiN<N>(tm[a]);
      F->x[1][a] = OctreeHiN<N>(t1[a]);
    }
  }
  const vfloat<N> rootEnter = Max(Max(F->e[0][0], F->e[0][1]), F->e[0][2]);
  const vfloat<N> rootExit = Min(Min(F->x[1][0], F->x[1][1]), F->x[1][2]);
  unsigned live = lanes & (Max(rootEnter, P.tmin) <= Min(rootExit, H.t)).Bits();
  if (!live) return;
  if constexpr (kStats) st.nTS += PopCount(live);
  const vfloat<N> never(-INFINITY);  // a leaf's exit that never ends the search
  if (nodes[0].childMask == 0u) {
    OctreePacket_Leaf<N, kTypes, kFast, kStats>(sc, nodes[0], P, H, live, never, anyHit, mailbox, st);
    return;
  }
  // Mirrored child m's widened entry: the largest of its axes' widened near
  // parameters (bit a of m picks the node's near or mid one).
  auto entry = [](const Frame& G, unsigned m) {
    return Max(Max(G.e[m & 1u][0], G.e[(m >> 1) & 1u][1]), G.e[(m >> 2) & 1u][2]);
  };
  // The lanes of `in` that meet mirrored child m of G's node, with the
  // closest hits at hitT.
  auto meetOf = [&](const Frame& G, unsigned m, unsigned in, vfloat<N> hitT) __attribute__((always_inline)) {
    const vfloat<N> cx = Min(Min(G.x[m & 1u][0], G.x[(m >> 1) & 1u][1]), G.x[(m >> 2) & 1u][2]);
    return in & (Max(entry(G, m), P.tmin) <= Min(cx, hitT)).Bits();
  };
  // The lanes of `in` that meet each of the stored children `mine`.
  auto meetAll = [&](Frame& G, unsigned in, unsigned mine) __attribute__((always_inline)) {
    const vfloat<N> hitT = H.t;
    unsigned todo = 0u;
    for (; mine; mine &= mine - 1u) {
      const unsigned m = static_cast<unsigned>(LowestBit(mine));
      const unsigned meet = meetOf(G, m, in, hitT);
      G.in[m] = static_cast<std::uint8_t>(meet);
      todo |= (meet != 0u ? 1u : 0u) << m;
    }
    G.todo |= todo;
  };
  // G's node entered by the lanes of `in`: the lanes that meet each of its
  // stored children; lazily (kLazy, kOctreeLazyLanes or more lanes), in
  // increasing order up to the first that some lane meets, the rest left for
  // when the walk comes back to the node (deferred, below).
  auto enter = [&](Frame& G, unsigned in) __attribute__((always_inline)) {
    unsigned mine = OctreeMirroredChildren(nodes[G.node].childMask, signMask);
    G.todo = 0u;
    G.deferred = 0u;
    G.lanes = in;
    if (!kLazy || PopCount(in) < kOctreeLazyLanes) {
      meetAll(G, in, mine);
      return;
    }
    const vfloat<N> hitT = H.t;
    for (; mine; mine &= mine - 1u) {
      const unsigned m = static_cast<unsigned>(LowestBit(mine));
      const unsigned meet = meetOf(G, m, in, hitT);
      G.in[m] = static_cast<std::uint8_t>(meet);
      if (meet) {
        G.todo = 1u << m;
        G.first = m;
        G.deferred = mine & (mine - 1u);
        return;
      }
    }
  };
  F->node = 0u;
  enter(*F, live);
  for (;;) {
    if (kLazy && F->todo == 0u && F->deferred != 0u) {
      // The children after the first met one, m, are met only now, with the
      // hit as it is: the search visits a child only where its entry lies
      // at or before the hit, which only nears, so they are the children the
      // walk would have visited had it met them on entry (the same visits,
      // order and counts). Each such child m' > m is not a subset of m: on
      // some axis a, m' is the node's far half and m its near half, so the
      // widened entry of m' is at least the node's widened mid parameter on
      // a. Where every lane that entered has its hit before the least of
      // those (on the axes where m is the near half), none is visited, and
      // none is met (a ray that hits the teapot in a stadium climbs the
      // stadium's chain of nodes without meeting their other children).
      const unsigned need = F->lanes & live;
      if (need) {
        vfloat<N> bound(INFINITY);
        for (int a = 0; a < 3; ++a)
          if (!((F->first >> a) & 1u)) bound = Min(bound, F->e[1][a]);
        if ((need & (H.t < bound).Bits()) != need) meetAll(*F, F->lanes, F->deferred);
      }
      F->deferred = 0u;
    }
    if (F->todo == 0u) {
      if (d == 0) return;
      F = &fr[--d];
      for (int a = 0; a < 3; ++a) c[a] >>= 1;
      continue;
    }
    const unsigned m = static_cast<unsigned>(LowestBit(F->todo));
    F->todo &= F->todo - 1u;
    const unsigned vis = F->in[m] & live & (entry(*F, m) <= H.t).Bits();
    if (!vis) continue;
    if constexpr (kStats) st.nTS += PopCount(vis);
    const std::uint32_t o = m ^ signMask;
    const OctreeNode& n = nodes[F->node];
    const std::uint32_t ci = n.first + PopCount(n.childMask & ((1u << o) - 1u));
    if (nodes[ci].childMask == 0u) {
      live &= ~OctreePacket_Leaf<N, kTypes, kFast, kStats>(sc, nodes[ci], P, H, vis, never, anyHit, mailbox, st);
      continue;
    }
    Frame* G = &fr[++d];
    for (int a = 0; a < 3; ++a) {
      c[a] = 2u * c[a] + ((o >> a) & 1u);
      const unsigned up = (m >> a) & 1u;
      G->e[0][a] = F->e[up][a];
      G->x[1][a] = F->x[up][a];
      const vfloat<N> tm = PlaneTN<N>(
          vfloat<N>(OctreePlane(hdr, a, static_cast<std::uint32_t>(d) + 1u, 2u * c[a] + 1u)), P.org[a], P.inv[a]);
      G->e[1][a] = OctreeLoN<N>(tm);
      G->x[0][a] = OctreeHiN<N>(tm);
    }
    G->node = ci;
    enter(*G, vis);
    F = G;
  }
}

// Closest hit (anyHit = 0) or any hit of the lanes in `active`, one pass per
// class of direction signs among them.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void OctreePacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> active,
                                       int anyHit, TraceStatsSum& st)
{
  const unsigned neg[3] = {P.invNeg[0].Bits(), P.invNeg[1].Bits(), P.invNeg[2].Bits()};
  // The lanes' mailboxes (--octree-mailbox on; kernels/octree.h).
  alignas(32) std::uint32_t mailboxes[CR_OCTREE_MAILBOX][N];
  std::uint32_t(*mailbox)[N] = nullptr;
  if (sc.octreeHeader->flags & CR_OCTREE_MAILBOX_ON) {
    for (auto& row : mailboxes) vint<N>(static_cast<int>(CR_NO_HIT)).Store(row);
    mailbox = mailboxes;
  }
  for (unsigned rest = active.Bits(); rest;) {
    const int l = LowestBit(rest);
    const unsigned signMask = ((neg[0] >> l) & 1u) | (((neg[1] >> l) & 1u) << 1) | (((neg[2] >> l) & 1u) << 2);
    unsigned cls = rest;
    for (int a = 0; a < 3; ++a) cls &= ((signMask >> a) & 1u) ? neg[a] : ~neg[a];
    rest &= ~cls;
    if ((sc.octreeHeader->flags & CR_OCTREE_MARGIN_RAY) && sc.octreeLazy)
      OctreePacket_SearchSigns<N, kTypes, kFast, kStats, true>(sc, P, H, cls, signMask, anyHit, mailbox, st);
    else if (sc.octreeHeader->flags & CR_OCTREE_MARGIN_RAY)
      OctreePacket_SearchSigns<N, kTypes, kFast, kStats, false>(sc, P, H, cls, signMask, anyHit, mailbox, st);
    else
      OctreePacket_TraceSigns<N, kTypes, kFast, kStats>(sc, P, H, cls, signMask, anyHit, mailbox, st);
  }
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void OctreePacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Packet_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](RayPacket<N>& P, HitPacket<N>& H, vbool<N> lanes, int anyHit, TraceStatsSum& st) {
        OctreePacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, lanes, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
