#include "bench/micro_common.h"

#include <cmath>
#include <map>
#include <mutex>

#include "host/scene/generate.h"

namespace cr::micro {

const Scene& BenchScene(const std::string& name)
{
  static std::mutex m;
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  std::lock_guard<std::mutex> lock(m);
  auto& s = cache[name];
  if (!s) s = std::make_unique<Scene>(name == "mesh" ? GenerateBumpySphere(100000) : GenerateSphereflake(4));
  return *s;
}

const ref::ReferenceTracer& BenchReference(const std::string& name)
{
  static std::mutex m;
  static std::map<std::string, std::unique_ptr<ref::ReferenceTracer>> cache;
  const Scene& scene = BenchScene(name);
  std::lock_guard<std::mutex> lock(m);
  auto& t = cache[name];
  if (!t) t = std::make_unique<ref::ReferenceTracer>(scene);
  return *t;
}

const std::vector<RayRecord>& BenchRays(const std::string& scene, RayKind kind)
{
  static std::mutex m;
  static std::map<std::pair<std::string, int>, std::vector<RayRecord>> cache;
  const ref::ReferenceTracer& tracer = BenchReference(scene);
  std::lock_guard<std::mutex> lock(m);
  auto& rays = cache[{scene, int(kind)}];
  if (rays.empty()) {
    RayGenOptions g;
    g.kind = kind;
    g.width = 128;
    g.height = 128;
    g.count = kind == RayKind::Primary ? 0 : 128 * 128;
    g.seed = 3;
    rays = GenerateRays(BenchScene(scene), tracer, g);
  }
  return rays;
}

std::vector<RayRecord> RaysAtOrigin(int n, float r, float dist, std::uint64_t seed)
{
  std::vector<RayRecord> rays(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double u = ToUnit(HashRandom(seed, 0, std::uint64_t(i)));
    const double v = ToUnit(HashRandom(seed, 1, std::uint64_t(i)));
    const double z = 2.0 * u - 1.0, phi = 2.0 * 3.14159265358979 * v;
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    const float o[3] = {float(dist * s * std::cos(phi)), float(dist * s * std::sin(phi)), float(dist * z)};
    float p[3];
    for (int a = 0; a < 3; ++a) p[a] = float((2.0 * ToUnit(HashRandom(seed, 2 + a, std::uint64_t(i))) - 1.0) * r);
    RayRecord& rec = rays[std::size_t(i)];
    for (int a = 0; a < 3; ++a) {
      rec.org[a] = o[a];
      rec.dir[a] = p[a] - o[a];
    }
    rec.tmin = 0.0f;
    rec.tmax = INFINITY;
  }
  return rays;
}

}  // namespace cr::micro
