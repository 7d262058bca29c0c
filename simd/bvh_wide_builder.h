// Flattening of the binary BVH into the CPU layouts of simd/bvh_wide.h
// (tinybvh's ConvertFrom idea: build once, convert per target).
#pragma once

#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

#include "host/accel/accel.h"
#include "host/core/big_array.h"
#include "host/scene/scene.h"
#include "simd/bvh_wide.h"
#include "simd/prims.h"
#include "simd/simd_kernels.h"

namespace cr::simd {

// The rows the kernels read of every type (SimdPrim<T>::Data, simd/<type>.h):
// the scene's own array where that is T, else computed here once (a
// type's MakeData). Bind points a KernelScene's arrays and ranges at them;
// the Scene must outlive this.
class SimdPrimData {
  template <class T>
  using Rows = std::vector<typename SimdPrim<T>::Data>;
  template <class T>
  static void Make(const std::vector<T>& prims, Rows<T>& rows)
  {
    if constexpr (!std::is_same_v<typename SimdPrim<T>::Data, T>) SimdPrim<T>::MakeData(prims, rows);
  }
  template <class T>
  static const void* RowsOf(const std::vector<T>& prims, const Rows<T>& rows)
  {
    if constexpr (std::is_same_v<typename SimdPrim<T>::Data, T>)
      return prims.data();
    else
      return rows.data();
  }

 public:
  explicit SimdPrimData(const Scene& scene) : scene_(&scene)
  {
#define CR_SIMD_MAKE_DATA_(T, U, a) Make(scene.a, a);
    CR_PRIM_TYPES(CR_SIMD_MAKE_DATA_)
#undef CR_SIMD_MAKE_DATA_
  }
  void Bind(KernelScene& sc) const
  {
#define CR_SIMD_BIND_DATA_(T, U, a)     \
  sc.prims[CR_PRIM_##U] = scene_->a.data(); \
  sc.data[CR_PRIM_##U] = RowsOf(scene_->a, a);
    CR_PRIM_TYPES(CR_SIMD_BIND_DATA_)
#undef CR_SIMD_BIND_DATA_
    sc.ranges = scene_->Ranges();
  }
  // Bytes of the computed rows.
  std::uint64_t Bytes() const
  {
    std::uint64_t b = 0;
#define CR_SIMD_DATA_BYTES_(T, U, a) b += a.size() * sizeof(typename SimdPrim<T>::Data);
    CR_PRIM_TYPES(CR_SIMD_DATA_BYTES_)
#undef CR_SIMD_DATA_BYTES_
    return b;
  }

 private:
  const Scene* scene_;
#define CR_SIMD_DATA_ARRAY_(T, U, a) Rows<T> a;
  CR_PRIM_TYPES(CR_SIMD_DATA_ARRAY_)
#undef CR_SIMD_DATA_ARRAY_
};

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
  BigVector<WideNode<N>> nodes;
  BigVector<WideLeaf> leaves;
#define CR_SIMD_PACK_ARRAY_(T, U, a) BigVector<typename SimdPrim<T>::template Pack<K>> a;  // each type's packs
  CR_PRIM_TYPES(CR_SIMD_PACK_ARRAY_)
#undef CR_SIMD_PACK_ARRAY_

  void Bind(KernelScene& sc) const override
  {
    sc.wideNodes = nodes.data();
    sc.wideLeaves = leaves.data();
#define CR_SIMD_BIND_PACKS_(T, U, a) sc.packs[CR_PRIM_##U] = a.data();
    CR_PRIM_TYPES(CR_SIMD_BIND_PACKS_)
#undef CR_SIMD_BIND_PACKS_
  }
  std::uint64_t Nodes() const override { return nodes.size(); }
  std::uint64_t Bytes() const override
  {
    std::uint64_t b = nodes.size() * sizeof(WideNode<N>) + leaves.size() * sizeof(WideLeaf);
#define CR_SIMD_PACK_BYTES_(T, U, a) b += a.size() * sizeof(typename SimdPrim<T>::template Pack<K>);
    CR_PRIM_TYPES(CR_SIMD_PACK_BYTES_)
#undef CR_SIMD_PACK_BYTES_
    return b;
  }
};

// Collapses `bvh` (host/accel/bvh_builder.cpp) into N-wide nodes, choosing
// which binary nodes become wide nodes so that the sum of their surface
// areas is least (a dynamic programme, bvh_wide_builder.cpp). Leaves keep
// their binary references, repacked K per pack and type from the rows `rows`
// points at (SimdPrimData::Bind). Supported (N, K): (4, 4), (8, 4), (8, 8);
// others throw RuntimeError.
std::unique_ptr<WideBVHBase> BuildWideBVH(const BVHData& bvh, const KernelScene& rows, int width, int packWidth);

}  // namespace cr::simd
