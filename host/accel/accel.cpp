#include "accel/accel.h"

#include <chrono>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace cr {

AccelKind ParseAccelKind(const std::string& s)
{
  if (s == "grid") return AccelKind::Grid;
  if (s == "octree") return AccelKind::Octree;
  if (s == "bvh") return AccelKind::BVH;
  throw InputError(fmt::format("unknown acceleration structure '{}' (expected grid, octree or bvh)", s));
}

const char* AccelKindName(AccelKind k)
{
  switch (k) {
    case AccelKind::Grid: return "grid";
    case AccelKind::Octree: return "octree";
    case AccelKind::BVH: return "bvh";
  }
  return "?";
}

void to_json(nlohmann::json& j, const AccelInfo& info)
{
  j = nlohmann::json{{"nodes", info.nodes},     {"leaves", info.leaves}, {"empty_leaves", info.emptyLeaves},
                     {"refs", info.refs},       {"bytes", info.bytes},   {"build_ms", info.buildMs},
                     {"params", info.params}};
}

AccelData BuildAccel(const Scene& scene, AccelKind kind, const AccelParams& params)
{
  AccelData data;
  data.kind = kind;
  auto t0 = std::chrono::steady_clock::now();
  switch (kind) {
    case AccelKind::Grid: data.grid = BuildGrid(scene, params, data.info); break;
    case AccelKind::Octree: data.octree = BuildOctree(scene, params, data.info); break;
    case AccelKind::BVH: data.bvh = BuildBVH(scene, params, data.info); break;
  }
  data.info.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return data;
}

}  // namespace cr
