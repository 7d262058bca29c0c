#include "simd/bvh_wide_builder.h"

#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"

namespace cr::simd {

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

  std::uint32_t Leaf(const BVHNode& b)
  {
    const PrimRanges& c = rows.ranges;
    const std::uint32_t* refs = bvh.refs.data() + b.first;
    auto packCount = [](std::uint32_t n) {
      const std::uint32_t p = (n + K - 1) / K;
      if (p > 255) throw RuntimeError("simd: BVH leaf too large for the wide layout");
      return static_cast<std::uint8_t>(p);
    };
    // Refs of a leaf are sorted, so each type is one run.
    WideLeaf leaf{};
    std::uint32_t i = 0;
#define CR_SIMD_LEAF_PACKS_(T, U, a)                                                                        \
  {                                                                                                       \
    std::uint32_t n = 0;                                                                                  \
    while (i + n < b.count && refs[i + n] < Prim_End(&c, CR_PRIM_##U)) ++n;                               \
    leaf.count[CR_PRIM_##U] = packCount(n);                                                               \
    leaf.first[CR_PRIM_##U] = Packs(out.a, refs + i, n, [&](auto& p, int l, std::uint32_t g) {           \
      SimdPrim<T>::template Fill<K>(p, l, PrimData<T>(rows)[Prim_Local(&c, CR_PRIM_##U, g)]);            \
    });                                                                                                   \
    i += n;                                                                                               \
  }
    CR_PRIM_TYPES(CR_SIMD_LEAF_PACKS_)
#undef CR_SIMD_LEAF_PACKS_
    const auto index = static_cast<std::uint32_t>(out.leaves.size());
    if (index >= kWideLeafFlag) throw RuntimeError("simd: too many BVH leaves for the wide layout");
    out.leaves.push_back(leaf);
    return index;
  }

  // Optimal collapse (the dynamic programme of Ylitie, Karras & Laine 2017,
  // "Efficient incoherent ray traversal on GPUs through compressed wide
  // BVHs", without their leaf decisions: leaves stay the binary leaves).
  // Cost of a collapse: the sum of the surface areas of the binary nodes that
  // become wide nodes (each is visited, in SAH terms, with probability
  // proportional to its area; leaf costs do not depend on the collapse).
  //   C(n, j): least cost of covering subtree n with at most j children,
  //            C(n, 1) = F(n) (n itself is a child: 0 for a leaf, W(n) else),
  //            C(n, j) = min(C(n, j - 1), min_i C(c0, i) + C(c1, j - i));
  //   W(n) = area(n) + min_i C(c0, i) + C(c1, N - i)   (n a wide node).
  // A greedy top-down collapse (open the child of largest area until N)
  // leaves the bottom of a balanced tree in wide nodes of 2 leaves: 585 BVH8
  // nodes for tetra's 1023 interior nodes, where this gives 147.
  std::vector<double> cost;             // C(n, j) at n * (N + 1) + j
  std::vector<std::uint8_t> choice;     // how C(n, j) was reached: 0 n itself, N + 1 as C(n, j - 1), else i
  std::vector<std::uint8_t> rootSplit;  // i of W(n)

  static double Area(const BVHNode& b)
  {
    const double ex = double(b.bmax[0]) - b.bmin[0], ey = double(b.bmax[1]) - b.bmin[1],
                 ez = double(b.bmax[2]) - b.bmin[2];
    return ex < 0.0 ? 0.0 : ex * ey + ey * ez + ez * ex;
  }

  void Plan()
  {
    const std::size_t n = bvh.nodes.size();
    cost.assign(n * (N + 1), 0.0);
    choice.assign(n * (N + 1), 0);
    rootSplit.assign(n, 0);
    // Children are stored after their parent (bvh_builder.cpp Flatten), so
    // a backward sweep sees children first.
    for (std::size_t b = n; b-- > 0;) {
      const BVHNode& bn = bvh.nodes[b];
      double* C = &cost[b * (N + 1)];
      std::uint8_t* how = &choice[b * (N + 1)];
      if (bn.count > 0) {
        for (int j = 1; j <= N; ++j) C[j] = 0.0, how[j] = 0;
        continue;
      }
      const double* C0 = &cost[std::size_t(bn.first) * (N + 1)];
      const double* C1 = &cost[std::size_t(bn.first + 1) * (N + 1)];
      double best = INFINITY;
      for (int i = 1; i < N; ++i)
        if (C0[i] + C1[N - i] < best) best = C0[i] + C1[N - i], rootSplit[b] = std::uint8_t(i);
      C[1] = Area(bn) + best;
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
    if (bn.count > 0) {
      kids[nKids++] = b;
    } else {
      const int i = rootSplit[b];
      Kids(bn.first, i, kids, nKids);
      Kids(bn.first + 1, N - i, kids, nKids);
    }
    std::uint32_t child[N];
    for (int i = 0; i < nKids; ++i) {
      const BVHNode& k = bvh.nodes[kids[i]];
      child[i] = k.count > 0 ? (kWideLeafFlag | Leaf(k)) : Node(kids[i]);
    }
    WideNode<N>& w = out.nodes[self];  // after the recursion: the vector may have grown
    for (int i = 0; i < N; ++i) {
      const bool used = i < nKids;
      for (int a = 0; a < 3; ++a) {
        w.lower[a][i] = used ? bvh.nodes[kids[i]].bmin[a] : INFINITY;
        w.upper[a][i] = used ? bvh.nodes[kids[i]].bmax[a] : -INFINITY;
      }
      w.child[i] = used ? child[i] : kWideEmptyLeaf;
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
    }
    out->nodes.push_back(root);
    return out;
  }
  out->nodes.reserve(bvh.nodes.size() / 2 + 1);
  Collapser<N, K> c{bvh, rows, *out, {}, {}, {}};
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
