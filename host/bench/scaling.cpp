#include "host/bench/scaling.h"

#include <fmt/format.h>

namespace cr::bench {

std::vector<SceneRef> ScalingScenes(bool quick)
{
  std::vector<SceneRef> out;
  auto add = [&](const std::string& kind, std::uint64_t n) {
    const std::string path = fmt::format("gen:{}:{}", kind, n);
    out.push_back(SceneRef{fmt::format("{}-{}", kind, n), path, path, true});
  };
  // Sphereflake depth d has (9^(d+1) - 1) / 8 spheres: 820 .. 5,380,840.
  for (int d = quick ? 2 : 3; d <= (quick ? 4 : 7); ++d) add("sphereflake", std::uint64_t(d));
  for (std::uint64_t n = 1000; n <= (quick ? 100000u : 10000000u); n *= 10) add("bumpy", n);
  add("stadium", quick ? 2 : 4);
  // Real meshes subdivided to 10^6 and 10^7 triangles, where ../shared has
  // them (not in the quick study).
  if (!quick)
    for (const char* mesh : {"bunny", "sponza"})
      if (!MeshPath(mesh).empty())
        for (std::uint64_t n : {1000000u, 10000000u}) add(fmt::format("subdiv-{}", mesh), n);
  return out;
}

std::vector<Combo> ScalingCombos()
{
  std::vector<Combo> c;
  for (AccelKind k : kAccelKinds) c.push_back(Combo{Backend::Simd, k, Precision::Robust, ""});
  if (EmbreeAvailable()) c.push_back(Combo{Backend::Embree, AccelKind::BVH, Precision::Robust, "packet8"});
  return c;
}

BenchOptions ScalingOptions(const BenchOptions& base)
{
  BenchOptions o = base;
  o.kinds = {RayKind::Primary, RayKind::Diffuse};
  o.repeat = base.quick ? 1 : 3;
  // Back to back: the 10^7 structures are not held together, and the memory
  // column is each configuration's alone.
  o.interleave = false;
  o.statsMaxPieces = 2000000;  // the 10^6 sizes (1,002,252 triangles) included
  return o;
}

}  // namespace cr::bench
