#include "simd/bvh_wide_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <mutex>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "host/core/error.h"

// The kernels' plane normal for TrianglePack's shortest edge (the same float
// operations as the scalar and SIMD kernels: no contraction, top
// CMakeLists.txt).
namespace cr::simd::pack_kernels {
#include "kernels/triangle.h"
}  // namespace cr::simd::pack_kernels

namespace cr::simd {

int PackShortEdge(const Triangle& t)
{
  float n[3];
  const int shared = pack_kernels::Triangle_PlaneNormal(&t, n);  // k's successor
  return shared == 0 ? 2 : shared - 1;
}

namespace {

template <int N, int K>
struct Collapser {
  Collapser(const BVHData& b, const KernelScene& r, WideBVH<N, K>& o) : bvh(b), rows(r), out(o) {}
  const BVHData& bvh;
  const KernelScene& rows;
  WideBVH<N, K>& out;

  // Where the next wide node, mixed-type leaf and pack of each type go.
  // The collapse walks the tree twice: counting (to size the arrays, and to
  // give each subtree of the top levels its place), then writing, the top
  // levels' subtrees in parallel. The layout is the sequential one (a wide
  // node, then each child's subtree or packs in order), whatever the
  // threads do.
  struct Cursor {
    std::uint64_t node = 0, leaf = 1;  // leaf 0: the empty leaf
    std::uint64_t pack[CR_NUM_PRIM_TYPES] = {};
  };
  // Wide levels written in parallel (8^2 subtrees).
  static constexpr int kParallelDepth = 2;

  template <class Pack, class Fill>
  std::uint32_t Packs(Pack* packs, std::uint64_t& at, const std::uint32_t* g, std::uint32_t n, Fill fill)
  {
    const std::uint64_t first = at;
    if (first + (n + K - 1) / K >= kWideLeafFlag) throw RuntimeError("simd: too many packs for the wide layout");
    for (std::uint32_t i = 0; i < n; i += K) {
      if (packs) {
        Pack& p = packs[at];
        p = Pack{};
        for (int l = 0; l < K; ++l) {
          p.g[l] = CR_NO_HIT;
          if (i + std::uint32_t(l) < n) {
            p.g[l] = g[i + l];
            fill(p, l, g[i + l]);
          }
        }
      }
      ++at;
    }
    return static_cast<std::uint32_t>(first);
  }

  struct Slot {
    std::uint32_t child, meta;
  };

  // A leaf of the refs [refs, refs + n), sorted (so each type is one run),
  // at `c` (written when `write`).
  Slot Leaf(const std::uint32_t* refs, std::uint32_t n, Cursor& c, bool write)
  {
    const PrimRanges& r = rows.ranges;
    auto packCount = [](std::uint32_t m) {
      const std::uint32_t p = (m + K - 1) / K;
      if (p > 255) throw RuntimeError("simd: BVH leaf too large for the wide layout");
      return static_cast<std::uint8_t>(p);
    };
    WideLeaf leaf{};
    std::uint32_t i = 0;
    int types = 0, type = 0;
#define CR_SIMD_LEAF_PACKS_(T, U, a)                                                                         \
  {                                                                                                        \
    std::uint32_t m = 0;                                                                                   \
    while (i + m < n && refs[i + m] < Prim_End(&r, CR_PRIM_##U)) ++m;                                      \
    leaf.count[CR_PRIM_##U] = packCount(m);                                                                \
    leaf.first[CR_PRIM_##U] = Packs(write ? out.a.data() : nullptr, c.pack[CR_PRIM_##U], refs + i, m,     \
                                    [&](auto& p, int l, std::uint32_t g) {                                 \
                                      SimdPrim<T>::template Fill<K>(                                       \
                                          p, l, PrimData<T>(rows)[Prim_Local(&r, CR_PRIM_##U, g)]);         \
                                    });                                                                    \
    if (m) ++types, type = CR_PRIM_##U;                                                                    \
    i += m;                                                                                                \
  }
    CR_PRIM_TYPES(CR_SIMD_LEAF_PACKS_)
#undef CR_SIMD_LEAF_PACKS_
    if (types == 1) return {kWideLeafFlag | leaf.first[type], WideLeafMeta(std::uint32_t(type), leaf.count[type])};
    const std::uint64_t index = c.leaf++;
    if (index >= kWideLeafFlag) throw RuntimeError("simd: too many BVH leaves for the wide layout");
    if (write) out.leaves[index] = leaf;
    return {kWideLeafFlag | static_cast<std::uint32_t>(index), kWideMixedLeaf};
  }

  // The refs of binary subtree b (a merged leaf: at most kMergeRefs) into
  // refs[m..], on the stack (a vector here was a malloc per merged leaf).
  void SubtreeRefs(std::uint32_t b, std::uint32_t* refs, std::uint32_t& m) const
  {
    const BVHNode& n = bvh.nodes[b];
    if (n.count > 0) {
      if (m + n.count > kMergeRefs) throw RuntimeError("simd: a merged BVH leaf holds too many references");
      for (std::uint32_t i = 0; i < n.count; ++i) refs[m++] = bvh.refs[n.first + i];
      return;
    }
    SubtreeRefs(n.first, refs, m);
    SubtreeRefs(n.first + 1, refs, m);
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
  // Kept per binary node for the writing walk; the costs C(n, .) and the
  // refs per type live only on the recursion's stack (at 10^7 nodes the
  // arrays of both were 700 MB).
  BigVector<std::uint8_t> choice;     // how C(n, j) was reached: 0 n itself, N + 1 as C(n, j - 1), else i
  BigVector<std::uint8_t> rootSplit;  // i of W(n)
  BigVector<std::uint8_t> asLeaf;     // F(n) = L(n)

  static double Area(const BVHNode& b)
  {
    const double ex = double(b.bmax[0]) - b.bmin[0], ey = double(b.bmax[1]) - b.bmin[1],
                 ez = double(b.bmax[2]) - b.bmin[2];
    return ex < 0.0 ? 0.0 : ex * ey + ey * ez + ez * ex;
  }

  // C(b, 1..N) and b's refs per type (up to kMergeRefs + 1: only small
  // subtrees merge; a binary leaf's exactly, at most 255).
  struct Sub {
    float C[N + 1];
    std::array<std::uint16_t, CR_NUM_PRIM_TYPES> refs;
  };
  // Binary levels planned in parallel.
  static constexpr int kPlanParallelDepth = 8;

  static std::uint32_t PackCount(const std::array<std::uint16_t, CR_NUM_PRIM_TYPES>& r, std::uint32_t& total)
  {
    std::uint32_t p = 0;
    total = 0;
    for (std::uint32_t m : r) p += (m + K - 1) / K, total += m;
    return p;
  }

  void Plan(std::uint32_t b, int depth, Sub& s)
  {
    const BVHNode& bn = bvh.nodes[b];
    std::uint8_t* how = &choice[std::size_t(b) * (N + 1)];
    float* C = s.C;
    std::uint32_t total = 0;
    if (bn.count > 0) {
      s.refs.fill(0);
      for (std::uint32_t i = bn.first; i < bn.first + bn.count; ++i)
        for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
          if (bvh.refs[i] < Prim_End(&rows.ranges, k)) {
            ++s.refs[k];
            break;
          }
      const float L = static_cast<float>(kPackCost * Area(bn) * PackCount(s.refs, total));
      for (int j = 1; j <= N; ++j) C[j] = L, how[j] = 0;
      asLeaf[b] = 1;
      rootSplit[b] = 0;
      return;
    }
    Sub s0, s1;
    if (depth < kPlanParallelDepth)
      tbb::parallel_invoke([&] { Plan(bn.first, depth + 1, s0); }, [&] { Plan(bn.first + 1, depth + 1, s1); });
    else
      Plan(bn.first, depth + 1, s0), Plan(bn.first + 1, depth + 1, s1);
    for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
      s.refs[k] = static_cast<std::uint16_t>(std::min<std::uint32_t>(s0.refs[k] + s1.refs[k], kMergeRefs + 1));
    const float* C0 = s0.C;
    const float* C1 = s1.C;
    float best = INFINITY;
    rootSplit[b] = 0;
    for (int i = 1; i < N; ++i)
      if (C0[i] + C1[N - i] < best) best = C0[i] + C1[N - i], rootSplit[b] = std::uint8_t(i);
    C[1] = static_cast<float>(Area(bn)) + best;
    const std::uint32_t p = PackCount(s.refs, total);
    const float L = static_cast<float>(kPackCost * Area(bn) * p);
    asLeaf[b] = 0;
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

  void Plan()
  {
    const std::size_t n = bvh.nodes.size();
    choice.resize(n * (N + 1));
    rootSplit.resize(n);
    asLeaf.resize(n);
    Sub root;
    Plan(0, 0, root);
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

  // The children of wide node b (binary node b: interior, or the root when
  // it is a leaf).
  int WideKids(std::uint32_t b, std::uint32_t* kids) const
  {
    int nKids = 0;
    if (asLeaf[b]) {
      kids[nKids++] = b;
    } else {
      const int i = rootSplit[b];
      Kids(bvh.nodes[b].first, i, kids, nKids);
      Kids(bvh.nodes[b].first + 1, N - i, kids, nKids);
    }
    return nKids;
  }

  // Child b of a wide node, at `c`: a wide node of its own or a leaf.
  Slot Kid(std::uint32_t b, Cursor& c, int depth, bool write)
  {
    if (!asLeaf[b]) return {write ? Node(b, c, depth) : Count(b, c, depth), 0u};
    const BVHNode& k = bvh.nodes[b];
    if (k.count > 0)  // a binary leaf: its refs in place, sorted by the builder
      return Leaf(bvh.refs.data() + k.first, k.count, c, write);
    std::uint32_t refs[kMergeRefs], m = 0;
    SubtreeRefs(b, refs, m);
    for (std::uint32_t i = 1; i < m; ++i)  // sorted by insertion: at most kMergeRefs
      for (std::uint32_t j = i; j > 0 && refs[j - 1] > refs[j]; --j) std::swap(refs[j - 1], refs[j]);
    return Leaf(refs, m, c, write);
  }

  static void Advance(Cursor& c, const Cursor& d)
  {
    c.node += d.node;
    c.leaf += d.leaf;
    for (unsigned k = 0; k < CR_NUM_PRIM_TYPES; ++k) c.pack[k] += d.pack[k];
  }

  // What the subtrees of the top levels hold (Count, kParallelDepth levels),
  // so that Node places them without counting again.
  std::mutex topMutex;
  std::map<std::uint32_t, Cursor> topCounts;

  // Advances `c` past wide node b's subtree, writing nothing; the top
  // levels' children counted in parallel.
  std::uint32_t Count(std::uint32_t b, Cursor& c, int depth)
  {
    const auto self = static_cast<std::uint32_t>(c.node);
    std::uint32_t kids[N];
    const int nKids = WideKids(b, kids);
    if (depth > kParallelDepth) {
      ++c.node;
      for (int i = 0; i < nKids; ++i) Kid(kids[i], c, depth + 1, false);
      return self;
    }
    // Node places the children of nodes above kParallelDepth by these.
    Cursor d[N];
    for (int i = 0; i < nKids; ++i) d[i] = Cursor{0, 0, {}};
    if (depth < kParallelDepth)
      tbb::parallel_for(0, nKids, [&](int i) { Kid(kids[i], d[i], depth + 1, false); });
    else
      for (int i = 0; i < nKids; ++i) Kid(kids[i], d[i], depth + 1, false);
    Cursor sum{1, 0, {}};
    for (int i = 0; i < nKids; ++i) Advance(sum, d[i]);
    {
      std::lock_guard<std::mutex> lock(topMutex);
      topCounts[b] = sum;
    }
    Advance(c, sum);
    return self;
  }

  // Writes wide node b at `c`, then its children's subtrees in order, and
  // advances `c` past them; b's index. The top levels' children are written
  // in parallel, each at the place Count found for it.
  std::uint32_t Node(std::uint32_t b, Cursor& c, int depth)
  {
    const std::uint64_t self = c.node++;
    if (self >= kWideLeafFlag) throw RuntimeError("simd: too many wide nodes for the wide layout");
    std::uint32_t kids[N];
    const int nKids = WideKids(b, kids);
    Slot slot[N];
    if (depth < kParallelDepth && nKids > 1) {
      Cursor at[N];
      for (int i = 0; i < nKids; ++i) {
        at[i] = c;
        if (!asLeaf[kids[i]])
          Advance(c, topCounts.at(kids[i]));
        else
          Kid(kids[i], c, depth + 1, false);
      }
      tbb::parallel_for(0, nKids, [&](int i) { slot[i] = Kid(kids[i], at[i], depth + 1, true); });
    } else {
      for (int i = 0; i < nKids; ++i) slot[i] = Kid(kids[i], c, depth + 1, true);
    }
    WideNode<N>& w = out.nodes[self];
    for (int i = 0; i < N; ++i) {
      const bool used = i < nKids;
      for (int a = 0; a < 3; ++a) {
        w.lower[a][i] = used ? bvh.nodes[kids[i]].bmin[a] : INFINITY;
        w.upper[a][i] = used ? bvh.nodes[kids[i]].bmax[a] : -INFINITY;
      }
      w.child[i] = used ? slot[i].child : kWideEmptyLeaf;
      w.meta[i] = used ? slot[i].meta : kWideMixedLeaf;
    }
    return static_cast<std::uint32_t>(self);
  }

  // Plans, counts, sizes the arrays and writes them.
  void Run()
  {
    Plan();
    Cursor total;
    Count(0, total, 0);
    if (total.node >= kWideLeafFlag || total.leaf >= kWideLeafFlag)
      throw RuntimeError("simd: too many wide nodes or leaves for the wide layout");
    out.nodes.resize(total.node);
    out.leaves.resize(total.leaf);
    out.leaves[0] = WideLeaf{};  // the empty leaf of unused slots
#define CR_SIMD_PACK_SIZE_(T, U, a) out.a.resize(total.pack[CR_PRIM_##U]);
    CR_PRIM_TYPES(CR_SIMD_PACK_SIZE_)
#undef CR_SIMD_PACK_SIZE_
    Cursor c;
    Node(0, c, 0);
  }
};

template <int N, int K>
std::unique_ptr<WideBVHBase> Build(const BVHData& bvh, const KernelScene& rows)
{
  auto out = std::make_unique<WideBVH<N, K>>();
  out->width = N;
  out->packWidth = K;
  if (bvh.refs.empty()) {
    // No primitives: a root with no children, which no ray enters.
    out->leaves.push_back(WideLeaf{});  // leaf 0: the empty leaf of unused slots
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
  Collapser<N, K> c(bvh, rows, *out);
  c.Run();
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
