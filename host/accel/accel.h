// Acceleration structures, built on the host into flat arrays that upload to a
// device unchanged (layouts in kernels/types.h). One entry point builds any of
// the three; grid, octree and BVH look alike from outside.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "kernels/types.h"
#include "host/scene/scene.h"

namespace cr {

// The structures, one entry each (enum name, command-line name): the CLI,
// the bench, the hard cases and the tests iterate kAccelKinds; nothing else
// lists them.
#define CR_ACCEL_KINDS(X) X(Grid, "grid") X(Octree, "octree") X(BVH, "bvh")

#define CR_ACCEL_ENUM(e, name) e,
enum class AccelKind { CR_ACCEL_KINDS(CR_ACCEL_ENUM) };
inline constexpr AccelKind kAccelKinds[] = {
#define CR_ACCEL_ENTRY(e, name) AccelKind::e,
    CR_ACCEL_KINDS(CR_ACCEL_ENTRY)
#undef CR_ACCEL_ENTRY
};
#undef CR_ACCEL_ENUM
AccelKind ParseAccelKind(const std::string& s);  // InputError on unknown names
const char* AccelKindName(AccelKind k);
std::string AccelKindNames();  // "grid, octree, bvh": for help texts and errors

struct AccelParams {
  double gridDensity = 0.0;  // Woo/Klimaszewski lambda: cells per primitive (0: default)
  int octreeLeaf = 0;        // max references per octree leaf (0: default)
  int octreeDepth = 0;       // max octree depth (0: default)
  int bvhLeaf = 0;           // max primitives per BVH leaf (0: default)
};

// Per-structure measures (Havran): nodes or cells, leaves, empty leaves,
// references, bytes of the uploaded arrays, build time.
struct AccelInfo {
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;
  std::uint64_t emptyLeaves = 0;
  std::uint64_t refs = 0;
  std::uint64_t bytes = 0;
  double buildMs = 0.0;
  std::string params;  // the parameters actually used, e.g. "density=4 res=64x64x32"
};
void to_json(nlohmann::json& j, const AccelInfo& info);

struct GridData {
  GridHeader header{};
  std::vector<std::uint32_t> cellStart;  // nCells + 1
  std::vector<std::uint32_t> refs;
};

struct OctreeData {
  OctreeHeader header{};
  std::vector<OctreeNode> nodes;
  std::vector<std::uint32_t> refs;
};

struct BVHData {
  std::vector<BVHNode> nodes;
  std::vector<std::uint32_t> refs;
};

struct AccelData {
  AccelKind kind = AccelKind::BVH;
  GridData grid;
  OctreeData octree;
  BVHData bvh;
  AccelInfo info;
};

// Builds the structure over the scene's unified primitives. Throws InputError
// for impossible parameters, RuntimeError when memory would not suffice.
AccelData BuildAccel(const Scene& scene, AccelKind kind, const AccelParams& params);

GridData BuildGrid(const Scene& scene, const AccelParams& params, AccelInfo& info);
OctreeData BuildOctree(const Scene& scene, const AccelParams& params, AccelInfo& info);
BVHData BuildBVH(const Scene& scene, const AccelParams& params, AccelInfo& info);

}  // namespace cr
