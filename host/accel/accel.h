// Acceleration structures, built on the host into flat arrays that upload to a
// device unchanged (layouts in kernels/types.h). One entry point builds any
// of them, and every structure looks alike from outside: a header record, a
// node array and the references (<Name>Data: header, Nodes(), refs).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/core/big_array.h"
#include "kernels/types.h"
#include "host/scene/scene.h"

namespace cr {

// The structures are the list CR_ACCEL_TYPES of kernels/types.h (enum name,
// upper and lower name, header and node layouts); the command-line name is
// the lower name. The CLI, the bench, the hard cases and the tests iterate
// kAccelKinds; nothing else lists them.
#define CR_ACCEL_ENUM(N, U, l, H, Nd) N,
enum class AccelKind { CR_ACCEL_TYPES(CR_ACCEL_ENUM) };
#undef CR_ACCEL_ENUM
inline constexpr AccelKind kAccelKinds[] = {
#define CR_ACCEL_ENTRY(N, U, l, H, Nd) AccelKind::N,
    CR_ACCEL_TYPES(CR_ACCEL_ENTRY)
#undef CR_ACCEL_ENTRY
};
AccelKind ParseAccelKind(const std::string& s);  // InputError on unknown names
const char* AccelKindName(AccelKind k);
std::string AccelKindNames();  // the command-line names, comma-separated: for help texts and errors

// The builders' parameters, one entry each: X(field, type, option, help);
// the CLI offers each as an option (0: the builder's default).
#define CR_ACCEL_PARAMS(X)                                                                     \
  X(gridDensity, double, "--grid-density", "Grid cells per primitive (Woo/Klimaszewski lambda)") \
  X(octreeLeaf, int, "--octree-leaf", "Max references per octree leaf")                        \
  X(octreeDepth, int, "--octree-depth", "Max octree depth")                                    \
  X(octreeBuild, std::string, "--octree-build",                                                 \
    "Octree subdivision: leaf (more than --octree-leaf references split; by default down to depth 10 and " \
    "on to 20 where the surface area heuristic finds it pays; --octree-depth D: down to D) or sah (the " \
    "heuristic everywhere)")                                                                    \
  X(octreeMailbox, std::string, "--octree-mailbox",                                              \
    "Octree walk: off (the default: the classic walk tests a primitive in every leaf it meets) or on (a "  \
    "per-ray mailbox skips a primitive already tested in an earlier leaf; same answers, fewer tests)") \
  X(octreeMargin, std::string, "--octree-margin",                                               \
    "Octree robustness: scene (the default, the classic octree: cells take their references with a margin " \
    "of the scene's size, which also bounds how small they get) or ray (cells without it, as deep as the " \
    "heuristic finds it pays, and a front-to-back search that widens each cell by the ray's own rounding)") \
  X(octreeRoot, std::string, "--octree-root",                                                   \
    "Octree root: centre (the scene's centre in the root's middle, where every level's mid planes cut it), " \
    "offset (at 0.45 of the root's side, a root 1.11x the scene) or auto (both built, the lower surface area " \
    "cost kept) (default: auto with --octree-margin ray, centre for the classic octree)")            \
  X(octreeLeafBox, std::string, "--octree-leaf-box",                                            \
    "Octree leaves with --octree-margin ray: on (the default: each leaf keeps the box of its primitives " \
    "clipped to its cell, and a ray that misses the box tests none of them) or off")               \
  X(bvhLeaf, int, "--bvh-leaf", "Max primitives per BVH leaf")                                 \
  X(bvhQuality, std::string, "--bvh-quality",                                                   \
    "BVH build: medium (binned SAH) or high (binned SAH with spatial splits, SBVH)")                 \
  X(bvhSahBlock, int, "--bvh-sah-block",                                                        \
    "BVH build: the SAH counts a leaf's cost in blocks of this many primitives (Embree's sahBlockSize; 0: " \
    "the backend's choice, 4 for simd on a scene of triangles only, else 1)")                    \
  X(hgridTopDensity, double, "--hgrid-top-density", "Hierarchical grid: root cells per primitive")       \
  X(hgridDensity, double, "--hgrid-density", "Hierarchical grid: child cells per reference of a crowded cell") \
  X(hgridLeaf, int, "--hgrid-leaf", "Hierarchical grid: most references a cell holds without a child grid") \
  X(hgridSkip, std::string, "--hgrid-skip",                                                      \
    "Hierarchical grid: skip empty space by each empty cell's distance to the nearest full one: on (the " \
    "default) or off (the walk steps through every cell)")
struct AccelParams {
#define CR_ACCEL_PARAM_FIELD(f, T, opt, help) T f{};
  CR_ACCEL_PARAMS(CR_ACCEL_PARAM_FIELD)
#undef CR_ACCEL_PARAM_FIELD
};

// Sets in `base` every parameter that `over` gives (not 0, not empty): a
// command line's parameters over a case's or a scene's own.
void OverrideAccelParams(AccelParams& base, const AccelParams& over);

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
  const std::vector<std::uint32_t>& Nodes() const { return cellStart; }
};

struct OctreeData {
  OctreeHeader header{};
  std::vector<OctreeNode> nodes;
  std::vector<std::uint32_t> refs;
  std::uint32_t chain = 0;  // OctreeChainLength, set by BuildOctree with the ray's margins
  const std::vector<OctreeNode>& Nodes() const { return nodes; }
};

struct BVHData {
  BVHHeader header{};
  BigVector<BVHNode> nodes;  // host/core/big_array.h: huge pages at scale
  BigVector<std::uint32_t> refs;
  const BigVector<BVHNode>& Nodes() const { return nodes; }
};

// Hierarchical grid (kernels/hgrid.h): the root grid, the child grids, and
// refs holding every grid's cell offsets, then the cells' references or
// child markers.
struct HGridData {
  GridHeader header{};
  std::vector<GridHeader> subs;
  std::vector<std::uint32_t> refs;
  const std::vector<GridHeader>& Nodes() const { return subs; }
};

// The built structure: the member of its kind (grid, octree, bvh, hgrid: the lower
// names of CR_ACCEL_TYPES) holds it; the others stay empty.
struct AccelData {
  AccelKind kind = AccelKind::BVH;
#define CR_ACCEL_DATA_MEMBER(N, U, l, H, Nd) N##Data l;
  CR_ACCEL_TYPES(CR_ACCEL_DATA_MEMBER)
#undef CR_ACCEL_DATA_MEMBER
  AccelInfo info;
};

// Builds the structure over the scene's unified primitives. Throws InputError
// for impossible parameters, RuntimeError when memory would not suffice.
AccelData BuildAccel(const Scene& scene, AccelKind kind, const AccelParams& params);

GridData BuildGrid(const Scene& scene, const AccelParams& params, AccelInfo& info);
OctreeData BuildOctree(const Scene& scene, const AccelParams& params, AccelInfo& info);
// The surface area heuristic's expected cost, in primitive tests, of a random
// ray through the scene's box in `tree` (--octree-root auto compares it).
double OctreeCost(const Scene& scene, const OctreeData& tree);
// Every node of an octree, each before its children: fn(node index, level,
// the cell's integer coordinates at that level).
void ForEachOctreeNode(const OctreeData& tree,
                       const std::function<void(std::uint32_t, std::uint32_t, const std::array<std::uint32_t, 3>&)>& fn);
// Down an octree's heaviest path (from the root, the child with the most
// references below it), the longest run of nodes each with exactly one
// interior child (the others leaves or empty), in levels: where most of a
// scene is a small detail in a large space (a teapot in a stadium), most
// rays descend such a chain.
std::uint32_t OctreeChainLength(const OctreeData& tree);
BVHData BuildBVH(const Scene& scene, const AccelParams& params, AccelInfo& info);
// Appends each node's parent to the references (after them; the header's
// `parents` says where; node 0's is 0) for the stackless walk (kernels/bvh.h,
// CR_BVH_STACKLESS) and counts their bytes; once.
void AddBVHParents(BVHData& bvh, AccelInfo& info);
HGridData BuildHGrid(const Scene& scene, const AccelParams& params, AccelInfo& info);

}  // namespace cr
