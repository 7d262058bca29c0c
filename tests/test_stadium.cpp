// Haines' "teapot in a stadium" taken literally (scenes/scale/teapot-stadium.nff:
// the SPD teapot on a ground 10^4 times its size, ringed by pillars): every
// structure and form, on every backend, answers it against the reference,
// from the teapot's camera and from across the stadium; and the forms made
// for it (the hierarchical grid, the octree with the ray's margins) refine
// around the teapot where the textbook grid does not. The generated stadium
// of the structures' own tests (gen:stadium, a sphereflake) has spheres; this
// one is the triangles of a mesh.
#include <cmath>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "host/trace/tracer.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

struct Form {
  const char* name;
  AccelKind accel;
  const char* octreeMargin;  // "" : the default
};
const Form kForms[] = {{"grid", AccelKind::Grid, ""},
                       {"octree", AccelKind::Octree, ""},
                       {"octree-ray", AccelKind::Octree, "ray"},
                       {"hgrid", AccelKind::HGrid, ""},
                       {"bvh", AccelKind::BVH, ""}};

// Rays from the pillars' ring (4,000 to 36,000 units out, 1 to 3,000 up) to
// points on and around the teapot: their float walks stray by more than the
// finest cells near the teapot, which must still not lose a hit.
std::vector<RayRecord> RaysFromAcross(int n)
{
  std::vector<RayRecord> rays;
  for (int i = 0; i < n; ++i) {
    const double a = 6.283185307179586 * i / n;
    const double r = 4000.0 + 32000.0 * ((i * 37) % n) / n;
    const glm::dvec3 from(r * std::cos(a), r * std::sin(a), 1.0 + 3000.0 * ((i * 11) % 17) / 17.0);
    const glm::dvec3 to(2.5 * std::sin(3.0 * i), 2.0 * std::cos(5.0 * i), 1.2 + 1.2 * std::sin(7.0 * i));
    const glm::dvec3 d = to - from;
    rays.push_back(RayRecord{{float(from.x), float(from.y), float(from.z)}, 0.0f, {float(d.x), float(d.y), float(d.z)},
                             INFINITY});
  }
  return rays;
}

}  // namespace

TEST_CASE("teapot in a stadium (scenes/scale/teapot-stadium.nff): every structure 0 wrong on every path, and the hierarchical forms refine around the teapot")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/scale/teapot-stadium.nff"));
  const auto clCache = test::OpenCLTestCacheDir();
  const std::vector<test::TracePath> paths = test::TracePaths();
  struct Set {
    const char* name;
    std::vector<RayRecord> rays;
  };
  const Set sets[] = {{"primary", test::MakeRays(scene, RayKind::Primary, 32)},
                      {"diffuse", test::MakeRays(scene, RayKind::Diffuse, 32)},
                      {"from across", RaysFromAcross(1024)}};
  double testsPerPrimary[std::size(kForms)] = {};
  for (const Set& set : sets)
    for (bool occlusion : {false, true})
      for (std::size_t f = 0; f < std::size(kForms); ++f)
        for (const test::TracePath& p : paths) {
          CAPTURE(std::string(set.name));
          CAPTURE(occlusion);
          CAPTURE(std::string(kForms[f].name));
          CAPTURE(std::string(p.name));
          TraceConfig cfg;
          cfg.backend = p.backend;
          cfg.variant = p.variant;
          cfg.accel = kForms[f].accel;
          cfg.params.octreeMargin = kForms[f].octreeMargin;
          cfg.stats = true;
          std::vector<HitRecord> hits;
          TraceStatsSum st;
          CreateTracer(scene, cfg)->Trace(set.rays, Tracer::NoTimes(), hits, occlusion, &st);
          const ref::CheckResult r =
              ref::CheckHits(test::CachedReference(scene), set.rays, hits, occlusion, Tracer::NoTimes());
          CHECK(r.wrong == 0);
          if (&set == &sets[0] && !occlusion && p.backend == Backend::Scalar) {
            testsPerPrimary[f] = double(st.nIT) / double(set.rays.size());
            std::size_t hit = 0;
            for (const HitRecord& h : hits) hit += h.prim != CR_NO_HIT;
            CHECK(hit == set.rays.size());  // the teapot, its floor or the ground
          }
        }
  MESSAGE("tests per primary ray (scalar): grid ", testsPerPrimary[0], ", octree ", testsPerPrimary[1], ", octree-ray ",
          testsPerPrimary[2], ", hgrid ", testsPerPrimary[3], ", bvh ", testsPerPrimary[4]);
  // The textbook grid's cells are the stadium's: the teapot falls in a few
  // (about 2,000 tests per ray), and the classic octree stops refining at
  // its scene-sized margin (about 150). The hierarchical grid and the
  // ray-margin octree refine around the teapot and test a few times the
  // BVH's primitives (12 and 13 against 3).
  CHECK(testsPerPrimary[0] > 100.0 * testsPerPrimary[3]);
  CHECK(testsPerPrimary[2] < 0.2 * testsPerPrimary[1]);
  CHECK(testsPerPrimary[3] < 6.0 * testsPerPrimary[4]);
  CHECK(testsPerPrimary[2] < 6.0 * testsPerPrimary[4]);
}
