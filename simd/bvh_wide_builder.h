// Flattening of the binary BVH into the CPU layouts of simd/bvh_wide.h
// (tinybvh's ConvertFrom idea: build once, convert per target).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "host/accel/accel.h"
#include "host/scene/scene.h"
#include "simd/bvh_wide.h"
#include "simd/simd_kernels.h"

namespace cr::simd {

// The ray-independent cone terms of every cone (bvh_wide.h ConeData).
std::vector<ConeData> MakeConeData(const Scene& scene);

// A collapsed BVH of any width, behind one interface.
class WideBVHBase {
 public:
  virtual ~WideBVHBase() = default;
  // Points the wide fields of `sc` at this structure's arrays.
  virtual void Bind(KernelScene& sc) const = 0;
  virtual std::uint64_t Nodes() const = 0;
  virtual std::uint64_t Bytes() const = 0;  // nodes + leaves + packs
  int width = 0, packWidth = 0;
};

template <int N, int K>
class WideBVH final : public WideBVHBase {
 public:
  std::vector<WideNode<N>> nodes;
  std::vector<WideLeaf> leaves;
  std::vector<SpherePack<K>> spheres;
  std::vector<TrianglePack<K>> triangles;
  std::vector<ConePack<K>> cones;

  void Bind(KernelScene& sc) const override
  {
    sc.wideNodes = nodes.data();
    sc.wideLeaves = leaves.data();
    sc.spherePacks = spheres.data();
    sc.trianglePacks = triangles.data();
    sc.conePacks = cones.data();
  }
  std::uint64_t Nodes() const override { return nodes.size(); }
  std::uint64_t Bytes() const override
  {
    return nodes.size() * sizeof(WideNode<N>) + leaves.size() * sizeof(WideLeaf) +
           spheres.size() * sizeof(SpherePack<K>) + triangles.size() * sizeof(TrianglePack<K>) +
           cones.size() * sizeof(ConePack<K>);
  }
};

// Collapses `bvh` (host/accel/bvh_builder.cpp) into N-wide nodes, choosing
// which binary nodes become wide nodes so that the sum of their surface
// areas is least (a dynamic programme, bvh_wide_builder.cpp). Leaves keep
// their binary references, repacked K per pack and type. Supported (N, K): (4, 4),
// (8, 4), (8, 8); others throw RuntimeError.
std::unique_ptr<WideBVHBase> BuildWideBVH(const BVHData& bvh, const Scene& scene, const std::vector<ConeData>& cones,
                                          int width, int packWidth);

}  // namespace cr::simd
