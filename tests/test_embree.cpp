// The Embree baseline backend (host/embree/): its answers mapped to our
// HitRecord are judged by the fp64 reference like any backend. With
// RTC_SCENE_FLAG_ROBUST it must give 0 wrong on the SPD scenes (triangles,
// patches, spheres as Embree points, cones as user geometry over our own
// Cone_Intersect); without it, Embree may miss marginal surfaces, but every
// primitive it names must be a real intersection (the id mapping) and every
// occluder it reports must occlude.
#include "host/core/error.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

TraceConfig EmbreeConfig(const char* variant)
{
  TraceConfig c;
  c.backend = Backend::Embree;
  c.variant = variant;
  return c;
}

}  // namespace

TEST_CASE("embree: robust variants give 0 wrong on SPD scenes with every primitive type")
{
  if (!EmbreeAvailable()) {
    MESSAGE("SKIPPED: this build has no Embree");
    return;
  }
  // 16-wide packets where Embree and the CPU have them (AVX-512): an input
  // error elsewhere.
  std::vector<const char*> robustVariants{"single-robust", "packet8-robust"};
  try {
    CreateTracer(test::CachedScene(test::SpdPath("tetra")), EmbreeConfig("packet16"));
    robustVariants.push_back("packet16-robust");
  } catch (const InputError& e) {
    MESSAGE("packet16 not run: ", e.what());
  }
  for (const std::string& name : test::Scenes({"tetra", "teapot", "balls", "rings", "tree"})) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse}) {
      const auto rays = test::MakeRays(scene, kind, 48);
      for (const char* variant : robustVariants) {
        INFO(name, " ", RayKindName(kind), " ", variant);
        const auto r = test::CheckTracer(scene, EmbreeConfig(variant), rays, test::IsOcclusion(kind));
        CHECK(r.wrong == 0);
        CHECK(r.agree + r.ties == rays.size());
      }
      for (const char* variant : {"single", "packet8"}) {
        INFO(name, " ", RayKindName(kind), " ", variant);
        const auto r = test::CheckTracer(scene, EmbreeConfig(variant), rays, test::IsOcclusion(kind));
        CHECK(r.wrongNotOnPrim == 0);
      }
    }
  }
}

TEST_CASE("embree: unified hits name the piece, with barycentrics of every triangle piece")
{
  if (!EmbreeAvailable()) {
    MESSAGE("SKIPPED: this build has no Embree");
    return;
  }
  const Scene& scene = test::CachedScene(test::SpdPath("gears"));  // polygons split into pieces
  const auto rays = test::MakeRays(scene, RayKind::Primary, 32);
  TraceConfig c = EmbreeConfig("single-robust");
  auto ids = CreateTracer(scene, c);
  c.unifiedHits = true;
  auto unified = CreateTracer(scene, c);
  std::vector<HitRecord> a, b;
  ids->Trace(rays, a, false, nullptr);
  unified->Trace(rays, b, false, nullptr);
  std::size_t nHit = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    REQUIRE((a[i].prim == CR_NO_HIT) == (b[i].prim == CR_NO_HIT));
    if (a[i].prim == CR_NO_HIT) continue;
    ++nHit;
    CHECK(b[i].prim < scene.NumUnified());
    CHECK(scene.IdOfUnified(b[i].prim) == a[i].prim);
    CHECK(a[i].t == b[i].t);
  }
  CHECK(nHit > rays.size() / 4);
}

TEST_CASE("embree: bad parameters are input errors")
{
  if (!EmbreeAvailable()) {
    MESSAGE("SKIPPED: this build has no Embree");
    return;
  }
  const Scene& scene = test::CachedScene(test::SpdPath("tetra"));
  TraceConfig c = EmbreeConfig("packet32");
  CHECK_THROWS_AS(CreateTracer(scene, c), InputError);
  c = EmbreeConfig("single");
  c.accel = AccelKind::Grid;
  CHECK_THROWS_AS(CreateTracer(scene, c), InputError);
  c = EmbreeConfig("single");
  c.precision = Precision::Fast;
  CHECK_THROWS_AS(CreateTracer(scene, c), InputError);
  c = EmbreeConfig("single");
  c.stats = true;
  CHECK_THROWS_AS(CreateTracer(scene, c), InputError);
}
