#include "simd/bvh_wide_builder.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"

// The kernels' plane normal for TrianglePack (the same float operations as
// the scalar and SIMD kernels: no contraction, top CMakeLists.txt).
namespace cr::simd::pack_kernels {
#include "kernels/triangle.h"
}  // namespace cr::simd::pack_kernels

namespace cr::simd {

int PackPlaneNormal(const Triangle& t, float n[3])
{
  return pack_kernels::Triangle_PlaneNormal(&t, n);
}

namespace {

template <int N, int K>
struct Collapser {
  const BVHData& bvh;
  const KernelScene& rows;
  WideBVH<N, K>& out;

  template <class Pack, class Fill>
  std::uint32_t Packs(std::vector<Pack>& packs, const std::uint32_t* g, std::uint32_t n, Fill fill)
  {
    const auto first = static_cast<std::uint32_t>(packs.size());
    for (std::uint32_t i = 0; i < n; i += K) {
      Pack p{};
      for (int l = 0; l < K; ++l) {
        p.g[l] = CR_NO_HIT;
        if (i + std::uint32_t(l) < n) {
          p.g[l] = g[i + l];
          fill(p, l, g[i + l]);
        }
      }
      packs.push_back(p);
    }
    return first;
  }

  struct Slot {
    std::uint32_t child, meta;
  };

  // A leaf of the refs [refs, refs + n), sorted (so each type is one run).
  Slot Leaf(const std::uint32_t* refs, std::uint32_t n)
  {
    const PrimRanges& c = rows.ranges;
    auto packCount = [](std::uint32_t m) {
      const std::uint32_t p = (m + K - 1) / K;
      if (p > 255) throw RuntimeError("simd: BVH leaf too large for the wide layout");
      return static_cast<std::uint8_t>(p);
    };
    WideLeaf leaf{};
    std::uint32_t i = 0;
    int types = 0, type = 0;
#define CR_SIMD_LEAF_PACKS_(T, U, a)                                                                        \
  {                                                                                                       \
    std::uint32_t m = 0;                                                                                  \
    while (i + m < n && refs[i + m] < Prim_End(&c, CR_PRIM_##U)) ++m;                                     \
    leaf.count[CR_PRIM_##U] = packCount(m);                                                               \
    leaf.first[CR_PRIM_##U] = Packs(out.a, refs + i, m, [&](auto& p, int l, std::uint32_t g) {           \
      SimdPrim<T>::template Fill<K>(p, l, PrimData<T>(rows)[Prim_Local(&c, CR_PRIM_##U, g)]);            \
    });                                                                                                   \
    if (m) ++types, type = CR_PRIM_##U;                                                                   \
    i += m;                                                                                               \
  }
    CR_PRIM_TYPES(CR_SIMD_LEAF_PACKS_)
#undef CR_SIMD_LEAF_PACKS_
    if (types == 1) {
      if (leaf.first[type] >= kWideLeafFlag) throw RuntimeError("simd: too many packs for the wide layout");
      return {kWideLeafFlag | leaf.first[type], WideLeafMeta(std::uint32_t(type), leaf.count[type])};
    }
    const auto index = static_cast<std::uint32_t>(out.leaves.size());
    if (index >= kWideLeafFlag) throw RuntimeError("simd: too many BVH leaves for the wide layout");
    out.leaves.push_back(leaf);
    return {kWideLeafFlag | index, kWideMixedLeaf};
  }

  // The refs of binary subtree b in one sorted run (a merged leaf).
  void SubtreeRefs(std::uint32_t b, std::vector<std::uint32_t>& refs) const
  {
    const BVHNode& n = bvh.nodes[b];
    if (n.count > 0) {
      refs.insert(refs.end(), bvh.refs.begin() + n.first, bvh.refs.begin() + n.first + n.count);
      return;
    }
    SubtreeRefs(n.first, refs);
    SubtreeRefs(n.first + 1, refs);
  }

  // Optimal collapse (the dynamic programme of Ylitie, Karras & Laine 2017,
  // "Efficient incoherent ray traversal on GPUs through compressed wide
  // BVHs"), with their leaf decision: a binary subtree of at most
  // kMergeRefs refs may become one leaf. In SAH terms (each slot is entered
  // with probability proportional to its area):
  //   C(n, j): least cost of covering subtree n with at most j children,
  //            C(n, 1) = F(n) (n itself is a child),
  //            C(n, j) = min(C(n, j - 1), min_i C(c0, i) + C(c1, j - i));
  //   F(n) = min(W(n), L(n)),  L(n) = kPackCost area(n) packs(n) (a leaf:
  //            its refs' packs, per type ceil(refs / K); a binary leaf is
  //            always one, an interior node only up to kMergeRefs refs);
  //   W(n) = area(n) + min_i C(c0, i) + C(c1, N - i)   (n a wide node).
  // A greedy top-down collapse (open the child of largest area until N)
  // leaves the bottom of a balanced tree in wide nodes of 2 leaves: 585 BVH8
  // nodes for tetra's 1023 interior nodes, where this gives 147. Merging
  // fills the packs: the binary builder's leaves (at most 4 refs, chosen by a
  // SAH that counts single tests) average fewer than 2 refs, so a pack of 4
  // held mostly empty lanes.
  // Tuned on bunny, sponza, gears and tetra (diffuse and shadow rays, AVX2
  // single): pack cost 1 or 2 and up to K or 2K refs within 2% of each
  // other, all 8-12% faster than no merging; 0.5 worse on gears.
  static constexpr double kPackCost = 2.0;
  static constexpr std::uint32_t kMergeRefs = 2 * K;
  std::vector<float> cost;              // C(n, j) at n * (N + 1) + j (float: 36 bytes a node at 10^7 nodes)
  std::vector<std::uint8_t> choice;     // how C(n, j) was reached: 0 n itself, N + 1 as C(n, j - 1), else i
  std::vector<std::uint8_t> rootSplit;  // i of W(n)
  std::vector<std::uint8_t> asLeaf;     // F(n) = L(n)

  static double Area(const BVHNode& b)
  {
    const double ex = double(b.bmax[0]) - b.bmin[0], ey = double(b.bmax[1]) - b.bmin[1],
                 ez = double(b.bmax[2]) - b.bmin[2];
    return ex < 0.0 ? 0.0 : ex * ey + ey * ez + ez * ex;
  }

  void Plan()
  {
    const std::size_t n = bvh.nodes.size();
    cost.assign(n * (N + 1), 0.0f);
    choice.assign(n * (N + 1), 0);
    rootSplit.assign(n, 0);
    asLeaf.assign(n, 0);
    // Refs per type of each subtree (up to kMergeRefs + 1: only small ones matter).
    std::vector<std::array<std::uint32_t, CR_NUM_PRIM_TYPES>> refsOf(n);
    auto packs = [](const std::array<std::uint32_t, CR_NUM_PRIM_TYPES>& r, std::uint32_t& total) {
      std::uint32_t p = 0;
      total = 0;
      for (std::uint32_t m : r) p += (m + K - 1) / K, total += m;
      return p;
    };
    // Children are stored after their parent (bvh_builder.cpp Flatten), so
    // a backward sweep sees children first.
    for (std::size_t b = n; b-- > 0;) {
      const BVHNode& bn = bvh.nodes[b];
      float* C = &cost[b * (N + 1)];
      std::uint8_t* how = &choice[b * (N + 1)];
      std::uint32_t total = 0;
      if (bn.count > 0) {
        auto& r = refsOf[b];
        r.fill(0);
        for (std::uint32_t i = bn.first; i < bn.first + bn.count; ++i)
          for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
            if (bvh.refs[i] < Prim_End(&rows.ranges, k)) {
              ++r[k];
              break;
            }
        const float L = static_cast<float>(kPackCost * Area(bn) * packs(r, total));
        for (int j = 1; j <= N; ++j) C[j] = L, how[j] = 0;
        asLeaf[b] = 1;
        continue;
      }
      for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
        refsOf[b][k] = std::min(refsOf[bn.first][k] + refsOf[bn.first + 1][k], kMergeRefs + 1);
      const float* C0 = &cost[std::size_t(bn.first) * (N + 1)];
      const float* C1 = &cost[std::size_t(bn.first + 1) * (N + 1)];
      float best = INFINITY;
      for (int i = 1; i < N; ++i)
        if (C0[i] + C1[N - i] < best) best = C0[i] + C1[N - i], rootSplit[b] = std::uint8_t(i);
      C[1] = static_cast<float>(Area(bn)) + best;
      const std::uint32_t p = packs(refsOf[b], total);
      const float L = static_cast<float>(kPackCost * Area(bn) * p);
      if (total <= kMergeRefs && L <= C[1]) {
        C[1] = L;
        asLeaf[b] = 1;
      }
      how[1] = 0;
      for (int j = 2; j <= N; ++j) {
        C[j] = C[j - 1];
        how[j] = N + 1;
        for (int i = 1; i < j; ++i)
          if (C0[i] + C1[j - i] < C[j]) C[j] = C0[i] + C1[j - i], how[j] = std::uint8_t(i);
      }
    }
  }

  // The children C(b, j) chose.
  void Kids(std::uint32_t b, int j, std::uint32_t* kids, int& nKids) const
  {
    for (;;) {
      const std::uint8_t how = choice[std::size_t(b) * (N + 1) + std::size_t(j)];
      if (how == 0) {
        kids[nKids++] = b;
        return;
      }
      if (how == N + 1) {
        --j;
        continue;
      }
      Kids(bvh.nodes[b].first, how, kids, nKids);
      b = bvh.nodes[b].first + 1;
      j -= how;
    }
  }

  // Wide node for binary node b (interior, or the root when it is a leaf).
  std::uint32_t Node(std::uint32_t b)
  {
    const auto self = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.emplace_back();
    std::uint32_t kids[N];
    int nKids = 0;
    const BVHNode& bn = bvh.nodes[b];
    if (asLeaf[b]) {
      kids[nKids++] = b;
    } else {
      const int i = rootSplit[b];
      Kids(bn.first, i, kids, nKids);
      Kids(bn.first + 1, N - i, kids, nKids);
    }
    Slot slot[N];
    std::vector<std::uint32_t> refs;
    for (int i = 0; i < nKids; ++i) {
      if (!asLeaf[kids[i]]) {
        slot[i] = {Node(kids[i]), 0u};
        continue;
      }
      const BVHNode& k = bvh.nodes[kids[i]];
      if (k.count > 0) {  // a binary leaf: its refs in place, sorted by the builder
        slot[i] = Leaf(bvh.refs.data() + k.first, k.count);
        continue;
      }
      refs.clear();
      SubtreeRefs(kids[i], refs);
      std::sort(refs.begin(), refs.end());
      slot[i] = Leaf(refs.data(), static_cast<std::uint32_t>(refs.size()));
    }
    WideNode<N>& w = out.nodes[self];  // after the recursion: the vector may have grown
    for (int i = 0; i < N; ++i) {
      const bool used = i < nKids;
      for (int a = 0; a < 3; ++a) {
        w.lower[a][i] = used ? bvh.nodes[kids[i]].bmin[a] : INFINITY;
        w.upper[a][i] = used ? bvh.nodes[kids[i]].bmax[a] : -INFINITY;
      }
      w.child[i] = used ? slot[i].child : kWideEmptyLeaf;
      w.meta[i] = used ? slot[i].meta : kWideMixedLeaf;
    }
    return self;
  }
};

template <int N, int K>
std::unique_ptr<WideBVHBase> Build(const BVHData& bvh, const KernelScene& rows)
{
  auto out = std::make_unique<WideBVH<N, K>>();
  out->width = N;
  out->packWidth = K;
  out->leaves.push_back(WideLeaf{});  // leaf 0: the empty leaf of unused slots
  if (bvh.refs.empty()) {
    // No primitives: a root with no children, which no ray enters.
    WideNode<N> root;
    for (int i = 0; i < N; ++i) {
      for (int a = 0; a < 3; ++a) {
        root.lower[a][i] = INFINITY;
        root.upper[a][i] = -INFINITY;
      }
      root.child[i] = kWideEmptyLeaf;
      root.meta[i] = kWideMixedLeaf;
    }
    out->nodes.push_back(root);
    return out;
  }
  out->nodes.reserve(bvh.nodes.size() / 2 + 1);
  // The packs grow by push_back: reserved for half-full packs, so that at
  // 10^7 references they are not copied (and their pages faulted) again and
  // again as the vectors double.
#define CR_SIMD_PACK_RESERVE_(T, U, a) \
  out->a.reserve(2 * (Prim_End(&rows.ranges, CR_PRIM_##U) - rows.ranges.begin[CR_PRIM_##U]) / K + 1);
  CR_PRIM_TYPES(CR_SIMD_PACK_RESERVE_)
#undef CR_SIMD_PACK_RESERVE_
  Collapser<N, K> c{bvh, rows, *out, {}, {}, {}, {}};
  c.Plan();
  c.Node(0);
  return out;
}

}  // namespace

std::unique_ptr<WideBVHBase> BuildWideBVH(const BVHData& bvh, const KernelScene& rows, int width, int packWidth)
{
  if (width == 4 && packWidth == 4) return Build<4, 4>(bvh, rows);
  if (width == 8 && packWidth == 4) return Build<8, 4>(bvh, rows);
  if (width == 8 && packWidth == 8) return Build<8, 8>(bvh, rows);
  throw RuntimeError(fmt::format("simd: no wide BVH layout for width {} and pack width {}", width, packWidth));
}

}  // namespace cr::simd
