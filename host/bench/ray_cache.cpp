#include "host/bench/ray_cache.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/io/rays_io.h"

namespace cr::bench {

namespace fs = std::filesystem;

namespace {

// Bumped when GenerateRays or this cache's naming changes meaning.
constexpr int kRayCacheVersion = 2;  // 2: scenes with motion give rays with times

nlohmann::json Identity(const SceneRef& ref, const RaySetSpec& spec, int width, int height)
{
  nlohmann::json j{{"cache_version", kRayCacheVersion}, {"scene", ref.shown},       {"kind", RayKindName(spec.kind)},
                   {"count", spec.count},               {"seed", spec.seed},       {"width", width},
                   {"height", height}};
  std::error_code ec;
  if (!ref.generated) {
    j["scene_bytes"] = fs::file_size(ref.path, ec);
    const auto t = fs::last_write_time(ref.path, ec);
    j["scene_mtime"] = static_cast<std::int64_t>(t.time_since_epoch().count());
  }
  return j;
}

}  // namespace

void PrimaryImageSize(const Scene& scene, std::uint64_t count, int& width, int& height)
{
  const double aspect = scene.camera.height > 0 ? double(scene.camera.width) / double(scene.camera.height) : 1.0;
  const double n = double(std::max<std::uint64_t>(count, 1));
  width = std::max(1, int(std::lround(std::sqrt(n * aspect))));
  height = std::max(1, int(std::lround(n / width)));
}

RaySet GetRaySet(const std::string& dir, const SceneRef& ref, const Scene& scene, const ref::ReferenceTracer& tracer,
                 const RaySetSpec& spec)
{
  RaySet set;
  PrimaryImageSize(scene, spec.count, set.width, set.height);
  const nlohmann::json id = Identity(ref, spec, set.width, set.height);
  const fs::path base = fs::path(dir) / "rays" / fmt::format("{}-{}-{}-s{}", ref.name, RayKindName(spec.kind), spec.count, spec.seed);
  set.path = base.string() + ".rays";
  const std::string sidecar = base.string() + ".json";
  std::error_code ec;
  if (fs::is_regular_file(set.path, ec) && fs::is_regular_file(sidecar, ec)) {
    try {
      std::ifstream f(sidecar);
      nlohmann::json old = nlohmann::json::parse(f);
      if (old == id) {
        set.rays = ReadRays(set.path, &set.times);
        set.fromCache = true;
        return set;
      }
    } catch (const std::exception&) {
      // An unreadable cache entry is regenerated, never trusted.
    }
  }
  fs::create_directories(base.parent_path(), ec);
  if (ec) throw RuntimeError(fmt::format("{}: cannot create directory ({})", base.parent_path().string(), ec.message()));
  RayGenOptions g;
  g.kind = spec.kind;
  g.width = set.width;
  g.height = set.height;
  g.seed = spec.seed;
  g.count = spec.kind == RayKind::Primary ? 0 : spec.count;
  try {
    set.rays = GenerateRays(scene, tracer, g, &set.times);
  } catch (const InputError& e) {
    // A scene without secondary rays of this kind (no lit primary hit, say)
    // skips those rows (empty set) instead of ending the whole bench.
    if (spec.kind == RayKind::Primary) throw;
    Warn(fmt::format("{} (its {} rows are skipped)", e.what(), RayKindName(spec.kind)));
    set.rays.clear();
    set.times.clear();
    set.why = e.what();
    return set;
  }
  WriteRays(set.path, set.rays, set.times);
  const std::string text = id.dump(2) + "\n";
  WriteFileAtomically(sidecar, text.data(), text.size());
  return set;
}

}  // namespace cr::bench
