#include "host/accel/accel.h"

#include <chrono>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/error.h"

namespace cr {

void OverrideAccelParams(AccelParams& base, const AccelParams& over)
{
#define CR_ACCEL_PARAM_OVERRIDE(f, T, opt, help) \
  if (over.f != T{}) base.f = over.f;
  CR_ACCEL_PARAMS(CR_ACCEL_PARAM_OVERRIDE)
#undef CR_ACCEL_PARAM_OVERRIDE
}

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
#define CR_ACCEL_NAME(N, U, l, H, Nd) \
  case AccelKind::N: return #l;
    CR_ACCEL_TYPES(CR_ACCEL_NAME)
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
#define CR_ACCEL_BUILD(N, U, l, H, Nd) \
  case AccelKind::N: data.l = Build##N(scene, params, data.info); break;
    CR_ACCEL_TYPES(CR_ACCEL_BUILD)
#undef CR_ACCEL_BUILD
  }
  data.info.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return data;
}

}  // namespace cr
