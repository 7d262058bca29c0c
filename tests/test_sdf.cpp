// The SDF block (NFF extension `sdf` ... `sdf end`, docs/FORMATS.md): its
// statement, stored form and errors, its distance program against closed
// forms, and conformance against the fp64 reference on every structure,
// backend and precision on scenes/geometry/sdf.nff (smooth unions, a
// difference, a repetition, an intersection).
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/prims/sdf_steps.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

const char* kBall = "sdf -2 -2 -2 2 2 2 0.001 128 1.5\n  sphere 0 0 0 1\nsdf end\n";

}  // namespace

TEST_CASE("sdf statement (extension): one primitive per block, ids in file order, stored about the centre, errors")
{
  Scene s;
  ParseNFF(std::string("s 0 0 5 1\n") + "sdf 0 -1 -1 4 1 1 0.001 64 1.25\n"
                                        "  box 2 0 0 1 0.5 0.5\n  repeat 1 0 0 1 0 0\n    sphere 2 0 0 0.3\n  end\n"
                                        "  difference\nsdf end\np 3\n0 0 5\n1 0 5\n0 1 5\n",
           "snippet", s);
  REQUIRE(s.NumPrims() == 3);
  CHECK((s.prims[1].kind == PrimKind::kShape && s.prims[1].type == CR_PRIM_SDF));
  REQUIRE(s.sdfs.size() == 1);
  const Sdf& b = s.sdfs[0];
  CHECK(b.count == 5);
  CHECK(b.center[0] == 2.0f);
  CHECK(b.op[0].op == CR_SDF_BOX);
  CHECK(b.op[0].a[0] == 0.0f);  // about the centre
  CHECK(b.op[1].op == CR_SDF_REPEAT);
  CHECK(b.op[3].op == CR_SDF_END_REPEAT);
  CHECK(b.op[4].op == CR_SDF_DIFFERENCE);
  CHECK(b.eps == 0.001f);
  CHECK(b.steps == 64);
  CHECK(b.relax == 1.25f);
  CHECK(s.UnifiedIds() == std::vector<std::uint32_t>{0, 2, 1});
  // A ray down the x axis meets the box's face x = 1 outside the holes cut
  // at x = 1, 2, 3 (radius 0.3): at y = 0.4 the face at t = 4.
  const std::vector<RayRecord> rays = {RayRecord{{-3.0f, 0.4f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY},
                                       RayRecord{{-3.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY}};
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision prec : {Precision::Robust, Precision::Fp64, Precision::Fast}) {
      TraceConfig cfg;
      cfg.backend = backend;
      cfg.precision = prec;
      std::vector<HitRecord> hits;
      CreateTracer(s, cfg)->Trace(rays, hits, false, nullptr);
      REQUIRE(hits.size() == 2);
      INFO(BackendName(backend), " ", PrecisionName(prec));
      CHECK(hits[0].prim == 1);
      CHECK(std::fabs(hits[0].t - 4.0f) <= (prec == Precision::Fast ? 0.002f : 1e-5f));
      // Along the axis the ray enters the hole at x = 1 and meets its
      // far wall, the sphere x = 1.3, at t = 4.3.
      CHECK(hits[1].prim == 1);
      CHECK(std::fabs(hits[1].t - 4.3f) <= (prec == Precision::Fast ? 0.002f : 1e-5f));
    }

  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\n", ":2: truncated 'sdf' block");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsdf end\n", ":1: 'sdf': the block has no shape");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\nsphere 1 0 0 1\nsdf end\n",
                      ":1: 'sdf': 2 shapes left uncombined");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\nunion\nsdf end\n",
                      ":3: 'sdf': 'union' needs two operands");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nblob 0 0 0 1\nsdf end\n", ":2: 'sdf': unknown operation 'blob'");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nrepeat 1 1 1 2 2 2\nsphere 0 0 0 1\nsdf end\n",
                      "'repeat' is not closed");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\nend\nsdf end\n", ":3: 'sdf': 'end' without a 'repeat'");
  test::CheckNffError("sdf 0 0 0 0 1 1 0.001 64 1.5\nsphere 0 0 0 1\nsdf end\n", "the bound is empty on axis x");
  test::CheckNffError("sdf 0 0 0 1 1 1 0 64 1.5\nsphere 0 0 0 1\nsdf end\n", "eps must be positive");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 0 1.5\nsphere 0 0 0 1\nsdf end\n", "step budget must be 1 to 2^20");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 2\nsphere 0 0 0 1\nsdf end\n", "relaxation factor must be in [1, 2)");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 -1\nsdf end\n", ":2: 'sdf': a sphere's radius must be positive");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\nsdf stop\n", ":3: 'sdf': expected 'sdf end'");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nroundbox 0 0 0 1 1 1 2\nsdf end\n", "rounded box's radius");
  test::CheckNffError("sdf 0 0 0 1 1 1 0.001 64 1.5\nrepeat 1 1 1 0.5 2 2\nsphere 0 0 0 1\nend\nsdf end\n",
                      "copy count must be a whole number");
  std::string many = "sdf 0 0 0 1 1 1 0.001 64 1.5\n";
  for (int k = 0; k < 9; ++k) many += "sphere 0 0 0 1\n";
  test::CheckNffError(many + "sdf end\n", ":10: 'sdf': more than 8 operands pending");
  std::string longer = "sdf 0 0 0 1 1 1 0.001 64 1.5\nsphere 0 0 0 1\n";
  for (int k = 0; k < 12; ++k) longer += "sphere 0 0 0 1\nunion\n";
  test::CheckNffError(longer + "sdf end\n", "more than 24 operations in one block");
}

TEST_CASE("sdf: the distance program against closed forms (every leaf and operator, repetition)")
{
  Scene s;
  ParseNFF("sdf -10 -10 -10 10 10 10 0.001 64 1\n  sphere 1 0 0 2\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  box 0 0 0 1 2 3\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  torus 0 0 0 3 1\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  capsule 0 0 0 0 4 0 1\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  cylinder 0 0 0 2 1\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  sphere -1 0 0 2\n  sphere 1 0 0 2\n  intersection\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  sphere 0 0 0 2\n  sphere 2 0 0 1\n  difference\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  repeat 4 0 0 1 0 0\n  sphere 0 0 0 1\n  end\nsdf end\n"
           "sdf -10 -10 -10 10 10 10 0.001 64 1\n  sphere -1 0 0 1\n  sphere 1 0 0 1\n  smooth 1\nsdf end\n",
           "closed-forms", s);
  REQUIRE(s.sdfs.size() == 9);
  auto d = [&](int k, double x, double y, double z) { return RefDistance(s.sdfs[k], glm::dvec3(x, y, z)); };
  CHECK(d(0, 5, 0, 0) == doctest::Approx(2.0));
  CHECK(d(1, 3, 0, 0) == doctest::Approx(2.0));           // face
  CHECK(d(1, 4, 5, 3) == doctest::Approx(std::sqrt(18.0)));  // past an edge: (3, 3, 0) away
  CHECK(d(1, 0.5, 0, 0) == doctest::Approx(0.5));         // inside: to the nearest face
  CHECK(d(2, 3, 0, 0) == doctest::Approx(1.0));           // on the ring: the tube's centre
  CHECK(d(2, 0, 0, 0) == doctest::Approx(2.0));
  CHECK(d(3, 3, 2, 0) == doctest::Approx(2.0));           // beside the segment
  CHECK(d(3, 0, 7, 0) == doctest::Approx(2.0));           // past its end
  CHECK(d(4, 0, 3, 0) == doctest::Approx(2.0));           // above the cap
  CHECK(d(4, 5, 0, 0) == doctest::Approx(3.0));           // beside the side
  CHECK(d(5, 0, 3, 0) == doctest::Approx(std::sqrt(10.0) - 2.0));  // the lens
  CHECK(d(6, 1.5, 0, 0) == doctest::Approx(0.5));         // in the bite
  CHECK(d(7, 4, 2, 0) == doctest::Approx(1.0));           // a copy at x = 4
  CHECK(d(7, 8, 2, 0) == doctest::Approx(std::sqrt(20.0) - 1.0));  // no copy past x = 4
  CHECK(d(8, 0, 0, 0) == doctest::Approx(0.25));          // min(0, 0) - k / 4 ... |-0.25|
}

TEST_CASE("sdf: the SDF scene, every structure x CPU backend x precision against the fp64 reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/sdf.nff"));
  REQUIRE(scene.sdfs.size() == 4);
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast})
      test::CheckConformance(scene, "sdf", backend, p, 32);
}

TEST_CASE("sdf: a ball's hits lie on the sphere, rays from its surface do not find it again, budget misses")
{
  Scene s;
  ParseNFF(kBall, "ball", s);
  std::vector<RayRecord> rays;
  for (int k = 0; k < 64; ++k) {
    const double a = 0.1 * k, y = 0.95 * std::sin(0.37 * k);
    rays.push_back(RayRecord{{float(-5.0 * std::cos(a)), float(y), float(-5.0 * std::sin(a))},
                             0.0f,
                             {float(std::cos(a)), 0.0f, float(std::sin(a))},
                             INFINITY});
  }
  for (Precision p : {Precision::Robust, Precision::Fp64}) {
    TraceConfig cfg;
    cfg.precision = p;
    std::vector<HitRecord> hits;
    CreateTracer(s, cfg)->Trace(rays, hits, false, nullptr);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      INFO(PrecisionName(p), " ray ", i);
      REQUIRE(hits[i].prim == 0);
      // The sphere's own root, in double.
      const double y = rays[i].org[1];
      const double want = 5.0 - std::sqrt(1.0 - y * y);
      CHECK(std::fabs(hits[i].t - want) <= 2e-5 * 5.0 / std::sqrt(1.0 - y * y));
      // From the hit point outward and along the tangent: free.
      const double x = rays[i].org[0] + hits[i].t * rays[i].dir[0], z = rays[i].org[2] + hits[i].t * rays[i].dir[2];
      std::vector<RayRecord> out = {RayRecord{{float(x), float(y), float(z)}, 1e-4f, {float(x), float(y), float(z)}, INFINITY}};
      std::vector<HitRecord> oh;
      CreateTracer(s, cfg)->Trace(out, oh, true, nullptr);
      CHECK(oh[0].prim == CR_NO_HIT);
    }
  }
  // The march replay of `trace --stats`: every ray enters the ball's bound
  // once, a few evaluations each, more in robust mode (its refinement).
  {
    TraceConfig cfg;
    std::vector<HitRecord> hits;
    CreateTracer(s, cfg)->Trace(rays, hits, false, nullptr);
    const SdfMarchCount robust = CountSdfMarches(s, rays, hits, false, false);
    const SdfMarchCount fast = CountSdfMarches(s, rays, hits, false, true);
    CHECK(robust.rays == rays.size());
    CHECK(robust.marches == rays.size());
    CHECK(fast.evals >= 3 * fast.marches);
    CHECK(robust.evals > fast.evals);
    CHECK(robust.evals < 64 * robust.marches);
  }
  // A budget of 2 steps cannot reach the ball from 3 away: fast mode misses
  // (the budget is its); robust and fp64 march on to the reference's budget
  // and hit it, as the reference does.
  Scene tight;
  ParseNFF("sdf -2 -2 -2 2 2 2 0.001 2 1\n  sphere 0 0 0 1\nsdf end\n", "tight", tight);
  const std::vector<RayRecord> grazing = {RayRecord{{-5.0f, 0.999f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY}};
  for (Precision p : {Precision::Fast, Precision::Robust, Precision::Fp64}) {
    TraceConfig cfg;
    cfg.precision = p;
    std::vector<HitRecord> hits;
    CreateTracer(tight, cfg)->Trace(grazing, hits, false, nullptr);
    INFO(PrecisionName(p));
    CHECK(hits[0].prim == (p == Precision::Fast ? CR_NO_HIT : 0u));
  }
  ref::ReferenceTracer reference(tight);
  std::vector<HitRecord> hits;
  CreateTracer(tight, TraceConfig{})->Trace(grazing, hits, false, nullptr);
  CHECK(ref::CheckHits(reference, grazing, hits, false).wrong == 0);
}

TEST_CASE("sdf: SIMD answers equal the scalar kernels' bit for bit (robust and fast, single and packet)")
{
  test::CheckSimdEqualsScalar(test::CachedScene(test::SourcePath("scenes/geometry/sdf.nff")), 32);
}

TEST_CASE("sdf: OpenCL, every structure, robust and fp64 against the reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/sdf.nff"));
  test::CheckOpenCLConformance({{"sdf", &scene}}, 24);
}

TEST_CASE("sdf: check, a block whose surface meets its bound's face (a cylinder's cap on the ground)")
{
  // Block 4 of the scene (primitive id 4) stands on the ground (y = 0, the
  // bound's lower face) with a cylinder whose cap lies on that face. Rays
  // from inside the cylinder leave it through the cap: a tracer's march
  // finds the cap within eps at the face, the reference march (in double)
  // leaves the bound first. An any-hit answer naming block 4 is a tie (the
  // ground occludes too), not "not an intersection of that primitive", as
  // check said until 2026-12-03 (the BVH's any-hit walk meets block 4 first).
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/sdf.nff"));
  const std::vector<RayRecord> rays = {
      RayRecord{{0.47636255621910095f, 0.5843818783760071f, 2.004457473754883f},
                0.0f,
                {-0.37355026602745056f, -0.8770174980163574f, 0.30215975642204285f},
                INFINITY},
      RayRecord{{-0.10853344202041626f, 3.1000075340270996f, 1.811821460723877f}, 0.5f, {0.0f, -1.0f, 0.0f}, INFINITY}};
  ref::ReferenceTracer reference(scene);
  std::vector<HitRecord> named(rays.size(), HitRecord{0.0f, 4u, 0.0f, 0.0f});
  const ref::CheckResult c = ref::CheckHits(reference, rays, named, true);
  CHECK(c.wrong == 0);
  CHECK(c.ties == rays.size());
  // Block 1 (the blob far to the side) is wrong for both.
  std::vector<HitRecord> far(rays.size(), HitRecord{0.0f, 1u, 0.0f, 0.0f});
  CHECK(ref::CheckHits(reference, rays, far, true).wrong == rays.size());
  // And the tracers' own answers, every CPU structure, robust.
  for (AccelKind a : kAccelKinds) {
    TraceConfig cfg;
    cfg.backend = Backend::Scalar;
    cfg.accel = a;
    std::vector<HitRecord> hits;
    CreateTracer(scene, cfg)->Trace(rays, hits, true, nullptr);
    INFO(AccelKindName(a));
    CHECK(ref::CheckHits(reference, rays, hits, true).wrong == 0);
  }
}
