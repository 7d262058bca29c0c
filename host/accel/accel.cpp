#include "host/accel/accel.h"

#include <chrono>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/error.h"

namespace cr {

std::string AccelKindNames()
{
  std::string names;
  for (AccelKind k : kAccelKinds) names += (names.empty() ? "" : ", ") + std::string(AccelKindName(k));
  return names;
}

AccelKind ParseAccelKind(const std::string& s)
{
  for (AccelKind k : kAccelKinds)
    if (s == AccelKindName(k)) return k;
  throw InputError(fmt::format("unknown acceleration structure '{}' (expected one of {})", s, AccelKindNames()));
}

const char* AccelKindName(AccelKind k)
{
  switch (k) {
#define CR_ACCEL_NAME(e, name) \
  case AccelKind::e: return name;
    CR_ACCEL_KINDS(CR_ACCEL_NAME)
#undef CR_ACCEL_NAME
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
