// Conformance: every structure on every CPU backend against the fp64
// reference, on every SPD scene and ray kind, at a reduced ray count
// (the full-size run is bench/conformance.sh).
#include "tests/test_util.h"

using namespace cr;

namespace {

constexpr auto& kAccels = kAccelKinds;
const RayKind kKinds[] = {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random};

void RunConformance(Backend backend, Precision precision, int size)
{
  for (const std::string& name : test::SpdScenes()) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    for (RayKind kind : kKinds) {
      const auto rays = test::MakeRays(scene, kind, size);
      for (AccelKind accel : kAccels) {
        TraceConfig cfg;
        cfg.backend = backend;
        cfg.accel = accel;
        cfg.precision = precision;
        auto r = test::CheckTracer(scene, cfg, rays, test::IsOcclusion(kind));
        INFO(name, " ", RayKindName(kind), " ", AccelKindName(accel), " ", BackendName(backend), " ",
             PrecisionName(precision), ": ", r.wrong, " wrong of ", r.rays,
             r.firstWrong.empty() ? std::string() : " (first " + std::to_string(r.firstWrong[0]) + ")");
        CHECK(r.rays == rays.size());
        CHECK(r.wrong == 0);
      }
    }
  }
}

}  // namespace

TEST_CASE("conformance: scalar robust, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Robust, 48);
}

TEST_CASE("conformance: scalar fp64, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Fp64, 32);
}
