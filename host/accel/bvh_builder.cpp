// BVH builder: binned SAH (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"), 32 bins per axis, subtrees built in parallel
// with oneTBB, then flattened depth-first into 32-byte BVHNodes whose two
// children are adjacent (types.h).
#include <algorithm>
#include <atomic>
#include <memory>
#include <numeric>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

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

struct Box {
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  void Extend(const Box& b)
  {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  void Extend(const glm::vec3& p)
  {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  float Area() const
  {
    glm::vec3 e = hi - lo;
    return (e.x < 0.0f) ? 0.0f : 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
};

struct BuildNode {
  Box box;
  std::unique_ptr<BuildNode> kids[2];
  std::uint32_t first = 0, count = 0;
};

struct Builder {
  std::vector<Box> boxes;
  std::vector<glm::vec3> centroids;
  std::vector<std::uint32_t> order;
  int maxLeaf = kDefaultLeaf;
  std::atomic<std::uint64_t> nodeCount{0};

  std::unique_ptr<BuildNode> Build(std::uint32_t begin, std::uint32_t end, int depth)
  {
    auto node = std::make_unique<BuildNode>();
    ++nodeCount;
    Box cb;
    for (std::uint32_t i = begin; i < end; ++i) {
      node->box.Extend(boxes[order[i]]);
      cb.Extend(centroids[order[i]]);
    }
    const std::uint32_t n = end - begin;
    auto leaf = [&]() {
      node->first = begin;
      node->count = n;
      std::sort(order.begin() + begin, order.begin() + end);  // group by type
      return std::move(node);
    };
    if (n <= 1) return leaf();

    std::uint32_t mid = begin;
    glm::vec3 ext = cb.hi - cb.lo;
    int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
    if (ext[axis] <= 0.0f) {
      // All centroids coincide: SAH cannot separate them.
      if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
      mid = begin + n / 2;
    } else if (depth >= kSahDepth) {
      mid = begin + n / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](std::uint32_t a, std::uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    } else {
      // Binned SAH over all three axes.
      float bestCost = INFINITY;
      int bestAxis = -1, bestSplit = -1;
      for (int a = 0; a < 3; ++a) {
        if (ext[a] <= 0.0f) continue;
        Box bin[kBins];
        std::uint32_t cnt[kBins] = {};
        const float scale = float(kBins) / ext[a];
        for (std::uint32_t i = begin; i < end; ++i) {
          int b = std::min(kBins - 1, static_cast<int>((centroids[order[i]][a] - cb.lo[a]) * scale));
          ++cnt[b];
          bin[b].Extend(boxes[order[i]]);
        }
        float rightArea[kBins];
        std::uint32_t rightCnt[kBins];
        Box acc;
        std::uint32_t c = 0;
        for (int b = kBins - 1; b > 0; --b) {
          acc.Extend(bin[b]);
          c += cnt[b];
          rightArea[b] = acc.Area();
          rightCnt[b] = c;
        }
        acc = Box{};
        c = 0;
        for (int b = 0; b < kBins - 1; ++b) {
          acc.Extend(bin[b]);
          c += cnt[b];
          if (c == 0 || rightCnt[b + 1] == 0) continue;
          float cost = acc.Area() * float(c) + rightArea[b + 1] * float(rightCnt[b + 1]);
          if (cost < bestCost) {
            bestCost = cost;
            bestAxis = a;
            bestSplit = b;
          }
        }
      }
      const float parentArea = node->box.Area();
      const float leafCost = float(n);
      const float splitCost = parentArea > 0.0f ? 1.0f + bestCost / parentArea : INFINITY;
      if (bestAxis < 0 || (n <= static_cast<std::uint32_t>(maxLeaf) && leafCost <= splitCost)) {
        if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
        mid = begin + n / 2;
        std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                         [&](std::uint32_t a, std::uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
      } else {
        const float scale = float(kBins) / ext[bestAxis];
        auto it = std::partition(order.begin() + begin, order.begin() + end, [&](std::uint32_t g) {
          int b = std::min(kBins - 1, static_cast<int>((centroids[g][bestAxis] - cb.lo[bestAxis]) * scale));
          return b <= bestSplit;
        });
        mid = static_cast<std::uint32_t>(it - order.begin());
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
  bld.boxes.resize(n);
  bld.centroids.resize(n);
  for (std::uint32_t g = 0; g < n; ++g) {
    Bounds b = scene.UnifiedBounds(g);
    bld.boxes[g].lo = b.lo;
    bld.boxes[g].hi = b.hi;
    bld.centroids[g] = 0.5f * (b.lo + b.hi);
  }
  bld.order.resize(n);
  std::iota(bld.order.begin(), bld.order.end(), 0u);

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
  out.refs = std::move(bld.order);
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
