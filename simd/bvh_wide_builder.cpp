#include "simd/bvh_wide_builder.h"

#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace cr::simd {

std::vector<ConeData> MakeConeData(const Scene& scene)
{
  // The operations of Cone_Intersect (kernels/intersect.h) in float, in its
  // order; this unit is compiled with -ffp-contract=off like the kernels.
  std::vector<ConeData> out(scene.cones.size());
  for (std::size_t i = 0; i < scene.cones.size(); ++i) {
    const Cone& c = scene.cones[i];
    ConeData& d = out[i];
    float w[3];
    for (int a = 0; a < 3; ++a) {
      w[a] = c.apex[a] - c.base[a];
      d.base[a] = c.base[a];
    }
    d.H = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    for (int a = 0; a < 3; ++a) d.w[a] = w[a] / d.H;
    d.r0 = c.baseRadius;
    d.k = (c.apexRadius - d.r0) / d.H;
  }
  return out;
}

namespace {

float Area(const BVHNode& n)
{
  const float ex = n.bmax[0] - n.bmin[0], ey = n.bmax[1] - n.bmin[1], ez = n.bmax[2] - n.bmin[2];
  return ex < 0.0f ? 0.0f : ex * ey + ey * ez + ez * ex;
}

template <int N, int K>
struct Collapser {
  const BVHData& bvh;
  const Scene& scene;
  const std::vector<ConeData>& cones;
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
    const PrimCounts c = scene.Counts();
    const std::uint32_t* refs = bvh.refs.data() + b.first;
    // Refs of a leaf are sorted, so each type is one run.
    std::uint32_t nS = 0, nT = 0;
    while (nS < b.count && refs[nS] < c.nSpheres) ++nS;
    while (nS + nT < b.count && refs[nS + nT] < c.nSpheres + c.nTriangles) ++nT;
    const std::uint32_t nC = b.count - nS - nT;
    auto packCount = [](std::uint32_t n) {
      const std::uint32_t p = (n + K - 1) / K;
      if (p > 255) throw RuntimeError("simd: BVH leaf too large for the wide layout");
      return static_cast<std::uint8_t>(p);
    };
    WideLeaf leaf{};
    leaf.count[0] = packCount(nS);
    leaf.count[1] = packCount(nT);
    leaf.count[2] = packCount(nC);
    leaf.first[0] = Packs(out.spheres, refs, nS, [&](SpherePack<K>& p, int l, std::uint32_t g) {
      const Sphere& s = scene.spheres[g];
      for (int a = 0; a < 3; ++a) p.center[a][l] = s.center[a];
      p.radius[l] = s.radius;
    });
    leaf.first[1] = Packs(out.triangles, refs + nS, nT, [&](TrianglePack<K>& p, int l, std::uint32_t g) {
      const Triangle& t = scene.triangles[g - c.nSpheres];
      for (int a = 0; a < 3; ++a) {
        p.v[0][a][l] = t.v0[a];
        p.v[1][a][l] = t.v1[a];
        p.v[2][a][l] = t.v2[a];
      }
    });
    leaf.first[2] = Packs(out.cones, refs + nS + nT, nC, [&](ConePack<K>& p, int l, std::uint32_t g) {
      const ConeData& d = cones[g - c.nSpheres - c.nTriangles];
      for (int a = 0; a < 3; ++a) {
        p.base[a][l] = d.base[a];
        p.w[a][l] = d.w[a];
      }
      p.H[l] = d.H;
      p.r0[l] = d.r0;
      p.k[l] = d.k;
    });
    const auto index = static_cast<std::uint32_t>(out.leaves.size());
    if (index >= kWideLeafFlag) throw RuntimeError("simd: too many BVH leaves for the wide layout");
    out.leaves.push_back(leaf);
    return index;
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
      kids[nKids++] = bn.first;
      kids[nKids++] = bn.first + 1;
    }
    while (nKids < N) {
      int best = -1;
      float bestArea = -1.0f;
      for (int i = 0; i < nKids; ++i) {
        const BVHNode& k = bvh.nodes[kids[i]];
        if (k.count == 0 && Area(k) > bestArea) {
          bestArea = Area(k);
          best = i;
        }
      }
      if (best < 0) break;
      const std::uint32_t open = kids[best];
      kids[best] = bvh.nodes[open].first;
      kids[nKids++] = bvh.nodes[open].first + 1;
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
std::unique_ptr<WideBVHBase> Build(const BVHData& bvh, const Scene& scene, const std::vector<ConeData>& cones)
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
  Collapser<N, K> c{bvh, scene, cones, *out};
  c.Node(0);
  return out;
}

}  // namespace

std::unique_ptr<WideBVHBase> BuildWideBVH(const BVHData& bvh, const Scene& scene, const std::vector<ConeData>& cones,
                                          int width, int packWidth)
{
  if (width == 4 && packWidth == 4) return Build<4, 4>(bvh, scene, cones);
  if (width == 8 && packWidth == 4) return Build<8, 4>(bvh, scene, cones);
  if (width == 8 && packWidth == 8) return Build<8, 8>(bvh, scene, cones);
  throw RuntimeError(fmt::format("simd: no wide BVH layout for width {} and pack width {}", width, packWidth));
}

}  // namespace cr::simd
