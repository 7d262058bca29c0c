// BVH builder: binned SAH (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"), 32 bins per axis, subtrees built in parallel
// with oneTBB, then flattened depth-first into 32-byte BVHNodes whose two
// children are adjacent (types.h).
#include <algorithm>
#include <atomic>
#include <memory>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include "host/accel/accel.h"
#include "host/core/error.h"

namespace cr {

namespace {

constexpr int kBins = 32;
constexpr int kDefaultLeaf = 4;
// Below this depth SAH decides; deeper, object-median splits bound the depth
// (<= 32 + log2(n)) so the traversal stack (CR_BVH_STACK = 64) never overflows.
constexpr int kSahDepth = 32;
constexpr std::uint32_t kParallelThreshold = 4096;

// Four floats (x, y, z and a lane kept at 0) in one register: GCC's and
// clang's vector extension, SSE on x86-64, whatever the target has elsewhere.
typedef float F4 __attribute__((vector_size(16)));
typedef std::int32_t I4 __attribute__((vector_size(16)));

struct Box {
  F4 lo = {INFINITY, INFINITY, INFINITY, 0.0f}, hi = {-INFINITY, -INFINITY, -INFINITY, 0.0f};
  // glm::min(lo, p) and glm::max(hi, p) lane by lane, NaN and signed zeros
  // included: (p < lo) ? p : lo, (hi < p) ? p : hi.
  void Extend(F4 plo, F4 phi)
  {
    lo = plo < lo ? plo : lo;
    hi = hi < phi ? phi : hi;
  }
  void Extend(const Box& b) { Extend(b.lo, b.hi); }
  void Extend(F4 p) { Extend(p, p); }
  float Area() const
  {
    const F4 e = hi - lo;
    return (e[0] < 0.0f) ? 0.0f : 2.0f * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
  }
};

struct BuildNode {
  Box box;
  std::unique_ptr<BuildNode> kids[2];
  std::uint32_t first = 0, count = 0;
};

// A reference with its box, moved with it by the partitions (Embree's
// PrimRef): every pass over a node's references reads them in order, not
// through an index into the scene-sized box array (at 10^7 references that
// gather missed the cache on nearly every read). The id rides in lo's
// fourth lane, masked off when the box is read.
struct PrimRef {
  F4 lo, hi;
  F4 Lo() const { return (F4)((I4)lo & I4{-1, -1, -1, 0}); }
  std::uint32_t Id() const { return __builtin_bit_cast(std::uint32_t, lo[3]); }
  F4 Centroid() const { return 0.5f * (Lo() + hi); }
};
static_assert(sizeof(PrimRef) == 32);

// Passes over more references than this split the range over oneTBB's
// threads; min, max and counts combine exactly, so the tree is the same.
constexpr std::uint32_t kParallelPass = 1u << 16;

// The node's box and its centroids' box.
struct Bounds2 {
  Box box, cb;
  void Add(const PrimRef& r)
  {
    box.Extend(r.Lo(), r.hi);
    cb.Extend(r.Centroid());
  }
  void Join(const Bounds2& o)
  {
    box.Extend(o.box);
    cb.Extend(o.cb);
  }
};

// The three axes' bins of a node, filled in one pass. A bin's box is
// written when its first reference arrives (cnt 0 -> 1) and read only where
// cnt > 0, so a node's bins need no initialisation beyond the counts (3 KB
// of boxes per node otherwise).
struct Bins {
  struct Raw {
    F4 lo, hi;
  };
  std::uint32_t cnt[3][kBins] = {};
  Raw bin[3][kBins];
  void Add(int a, int k, F4 lo, F4 hi)
  {
    Box b;
    if (cnt[a][k]++) b = Box{bin[a][k].lo, bin[a][k].hi};
    b.Extend(lo, hi);
    bin[a][k] = {b.lo, b.hi};
  }
  Box BoxOf(int a, int k) const { return Box{bin[a][k].lo, bin[a][k].hi}; }
  void Join(const Bins& o)
  {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < kBins; ++b) {
        if (!o.cnt[a][b]) continue;
        Box x;
        if (cnt[a][b]) x = BoxOf(a, b);
        x.Extend(o.BoxOf(a, b));
        bin[a][b] = {x.lo, x.hi};
        cnt[a][b] += o.cnt[a][b];
      }
  }
};

struct Builder {
  std::vector<PrimRef> refs;
  int maxLeaf = kDefaultLeaf;
  std::atomic<std::uint64_t> nodeCount{0};

  // add(acc, b, e) over [begin, end) into `out` (default-initialised),
  // in parallel when large. An out parameter, not a return value: a node's
  // Bins are 3.4 KB, and two return paths defeat the copy elision.
  template <class Acc, class Add>
  void Reduce(Acc& out, std::uint32_t begin, std::uint32_t end, Add add) const
  {
    if (end - begin <= kParallelPass) {
      add(out, begin, end);
      return;
    }
    out = tbb::parallel_reduce(
        tbb::blocked_range<std::uint32_t>(begin, end, kParallelPass / 4), Acc{},
        [&](const tbb::blocked_range<std::uint32_t>& r, Acc acc) {
          add(acc, r.begin(), r.end());
          return acc;
        },
        [](Acc x, const Acc& y) {
          x.Join(y);
          return x;
        });
  }

  std::unique_ptr<BuildNode> Build(std::uint32_t begin, std::uint32_t end, int depth)
  {
    auto node = std::make_unique<BuildNode>();
    ++nodeCount;
    Bounds2 nb;
    Reduce(nb, begin, end, [&](Bounds2& acc, std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) acc.Add(refs[i]);
    });
    node->box = nb.box;
    const Box& cb = nb.cb;
    const std::uint32_t n = end - begin;
    auto leaf = [&]() {
      node->first = begin;
      node->count = n;
      // group by type
      std::sort(refs.begin() + begin, refs.begin() + end,
                [](const PrimRef& x, const PrimRef& y) { return x.Id() < y.Id(); });
      return std::move(node);
    };
    if (n <= 1) return leaf();

    auto byCentroid = [](int axis) {
      return [axis](const PrimRef& x, const PrimRef& y) { return x.Centroid()[axis] < y.Centroid()[axis]; };
    };
    std::uint32_t mid = begin;
    const F4 ext = cb.hi - cb.lo;
    int axis = ext[0] > ext[1] ? (ext[0] > ext[2] ? 0 : 2) : (ext[1] > ext[2] ? 1 : 2);
    if (ext[axis] <= 0.0f) {
      // All centroids coincide: SAH cannot separate them.
      if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
      mid = begin + n / 2;
    } else if (depth >= kSahDepth) {
      mid = begin + n / 2;
      std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end, byCentroid(axis));
    } else {
      // Binned SAH over all three axes, binned in one pass.
      float scale[3];
      for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 0.0f ? float(kBins) / ext[a] : 0.0f;
      const F4 sc = {scale[0], scale[1], scale[2], 0.0f};
      Bins bins;
      Reduce(bins, begin, end, [&](Bins& acc, std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t i = b; i < e; ++i) {
          const PrimRef& r = refs[i];
          const F4 lo = r.Lo();
          const F4 f = (0.5f * (lo + r.hi) - cb.lo) * sc;
          for (int a = 0; a < 3; ++a) {
            if (ext[a] <= 0.0f) continue;
            const int k = std::min(kBins - 1, static_cast<int>(f[a]));
            acc.Add(a, k, lo, r.hi);
          }
        }
      });
      float bestCost = INFINITY;
      int bestAxis = -1, bestSplit = -1;
      for (int a = 0; a < 3; ++a) {
        if (ext[a] <= 0.0f) continue;
        const std::uint32_t* cnt = bins.cnt[a];
        // The splits after non-empty bins only: a split after an empty bin
        // costs what the split before it costs (the same two sets), and
        // only a strictly lower cost replaces the best, so skipping them
        // chooses the same split as sweeping all kBins - 1.
        int used[kBins], m = 0;
        for (int b = 0; b < kBins; ++b) {  // without a branch: which bins are empty is data
          used[m] = b;
          m += cnt[b] != 0;
        }
        float rightArea[kBins];
        std::uint32_t rightCnt[kBins];
        Box acc;
        std::uint32_t c = 0;
        for (int j = m - 1; j > 0; --j) {
          acc.Extend(bins.BoxOf(a, used[j]));
          c += cnt[used[j]];
          rightArea[j] = acc.Area();
          rightCnt[j] = c;
        }
        acc = Box{};
        c = 0;
        for (int j = 0; j < m - 1; ++j) {
          acc.Extend(bins.BoxOf(a, used[j]));
          c += cnt[used[j]];
          float cost = acc.Area() * float(c) + rightArea[j + 1] * float(rightCnt[j + 1]);
          if (cost < bestCost) {
            bestCost = cost;
            bestAxis = a;
            bestSplit = used[j];
          }
        }
      }
      const float parentArea = node->box.Area();
      const float leafCost = float(n);
      const float splitCost = parentArea > 0.0f ? 1.0f + bestCost / parentArea : INFINITY;
      if (bestAxis < 0 || (n <= static_cast<std::uint32_t>(maxLeaf) && leafCost <= splitCost)) {
        if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
        mid = begin + n / 2;
        std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end, byCentroid(axis));
      } else {
        const float s = scale[bestAxis];
        auto it = std::partition(refs.begin() + begin, refs.begin() + end, [&](const PrimRef& r) {
          int b = std::min(kBins - 1, static_cast<int>((r.Centroid()[bestAxis] - cb.lo[bestAxis]) * s));
          return b <= bestSplit;
        });
        mid = static_cast<std::uint32_t>(it - refs.begin());
        if (mid == begin || mid == end) mid = begin + n / 2;
      }
    }
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->kids[0] = Build(begin, mid, depth + 1); },
                           [&] { node->kids[1] = Build(mid, end, depth + 1); });
    } else {
      node->kids[0] = Build(begin, mid, depth + 1);
      node->kids[1] = Build(mid, end, depth + 1);
    }
    return node;
  }
};

void Store(const BuildNode& b, BVHNode& out)
{
  for (int a = 0; a < 3; ++a) {
    out.bmin[a] = b.box.lo[a];
    out.bmax[a] = b.box.hi[a];
  }
  out.first = b.first;
  out.count = b.count;
}

// Depth-first flattening: children of node i go to two adjacent new slots.
void Flatten(const BuildNode& b, std::uint32_t self, std::vector<BVHNode>& nodes, AccelInfo& info)
{
  Store(b, nodes[self]);
  if (b.count > 0 || !b.kids[0]) {
    ++info.leaves;
    return;
  }
  const auto first = static_cast<std::uint32_t>(nodes.size());
  nodes.resize(nodes.size() + 2);
  nodes[self].first = first;
  nodes[self].count = 0;
  Flatten(*b.kids[0], first, nodes, info);
  Flatten(*b.kids[1], first + 1, nodes, info);
}

}  // namespace

BVHData BuildBVH(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  if (params.bvhLeaf < 0 || params.bvhLeaf > 255)
    throw InputError(fmt::format("--bvh-leaf {} is not in 1..255", params.bvhLeaf));
  Builder bld;
  bld.maxLeaf = params.bvhLeaf > 0 ? params.bvhLeaf : kDefaultLeaf;
  const std::uint32_t n = scene.NumUnified();
  bld.refs.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t g = r.begin(); g < r.end(); ++g) {
      const Bounds b = scene.UnifiedBounds(g);
      bld.refs[g] = PrimRef{F4{b.lo.x, b.lo.y, b.lo.z, __builtin_bit_cast(float, g)}, F4{b.hi.x, b.hi.y, b.hi.z, 0.0f}};
    }
  });

  BVHData out;
  if (n == 0) {
    // An empty root leaf whose box no ray enters.
    BVHNode empty{};
    for (int a = 0; a < 3; ++a) {
      empty.bmin[a] = INFINITY;
      empty.bmax[a] = -INFINITY;
    }
    empty.count = 0;
    empty.first = 0;
    out.nodes.push_back(empty);
    out.header.nNodes = 1;
    info.params = fmt::format("leaf={} bins={}", bld.maxLeaf, kBins);
    info.nodes = 1;
    info.bytes = sizeof(BVHNode);
    return out;
  }
  std::unique_ptr<BuildNode> root = bld.Build(0, n, 0);
  out.nodes.reserve(bld.nodeCount.load());
  out.nodes.resize(1);
  Flatten(*root, 0, out.nodes, info);
  out.refs.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) out.refs[i] = bld.refs[i].Id();
  out.header.nNodes = static_cast<std::uint32_t>(out.nodes.size());
  out.header.nRefs = static_cast<std::uint32_t>(out.refs.size());
  info.nodes = out.nodes.size();
  info.refs = out.refs.size();
  info.emptyLeaves = 0;
  info.bytes = out.nodes.size() * sizeof(BVHNode) + out.refs.size() * sizeof(std::uint32_t);
  info.params = fmt::format("leaf={} bins={}", bld.maxLeaf, kBins);
  return out;
}

}  // namespace cr
