// The clipped quadric (NFF extension `quadric`, docs/FORMATS.md): its
// statement and stored form, and conformance against the fp64 reference on
// every structure, backend and precision, on the scene of every family
// (scenes/geometry/quadrics.nff) and on numerically hard ones (a ground
// ellipsoid 2e6 across seen from 30 above, a tiny quadric far away, rays
// leaving the surfaces).
#include <cmath>

#include "host/core/error.h"
#include "tests/test_util.h"

using namespace cr;

namespace {


// The hard scene: a ground ellipsoid 2e6 across under a camera 30 above,
// a bowl and a cooling tower standing on it, and a tiny ellipsoid (0.01
// across, 70 away) that AimedRays hits, and a small triangle.
const char* kHardScene =
    "v\nfrom 0 30 -60\nat 0 0 0\nup 0 1 0\nangle 50\nhither 0.01\nresolution 64 64\n"
    "b 0.2 0.2 0.3\nl 10 100 -50\n"
    "f 0.8 0.8 0.8 0.8 0 10 0 1\n"
    // ground: x^2 + 4 (y + 5e5)^2 + z^2 = 1e12, its top at y = 0
    "quadric 1 4 1 0 0 0 0 4e6 0 0 -1e6 -10 -1e6 1e6 1 1e6\n"
    // a bowl y = (x^2 + z^2) / 4, and a tower (x - 15)^2 + z^2 - (y - 5)^2 / 4 = 4
    "quadric 0.25 0 0.25 0 0 0 0 -1 0 0 -6 0 -6 6 9 6\n"
    "quadric 1 -0.25 1 0 0 0 -30 2.5 0 214.75 10 0 -5 20 10 5\n"
    // tiny ellipsoid, semi-axes 0.01 0.01 0.005, centred (0.5, 1, 40)
    "quadric 1e4 1e4 4e4 0 0 0 -1e4 -2e4 -3.2e6 64012499 0.48 0.98 39.99 0.52 1.02 40.01\n"
    // a marker triangle: the same type set as quadrics.nff (one set of OpenCL programs)
    "p 3\n-8 0 -6\n-6 0 -6\n-7 1.5 -6\n";

// Rays from the camera at points in and around the tiny ellipsoid.
std::vector<RayRecord> AimedRays()
{
  std::vector<RayRecord> rays;
  const float o[3] = {0.0f, 30.0f, -60.0f};
  for (int i = 0; i < 17; ++i)
    for (int j = 0; j < 17; ++j) {
      const float p[3] = {0.5f + 0.0015f * float(i - 8), 1.0f + 0.0015f * float(j - 8), 40.0f};
      RayRecord r{};
      for (int a = 0; a < 3; ++a) {
        r.org[a] = o[a];
        r.dir[a] = p[a] - o[a];
      }
      r.tmin = 0.0f;
      r.tmax = INFINITY;
      rays.push_back(r);
    }
  return rays;
}

}  // namespace

TEST_CASE("quadric statement (extension): stored about the box's centre, ids in file order, bounds, errors")
{
  Scene s;
  ParseNFF("s 0 0 0 1\nquadric 1 1 1 0 0 0 -2 0 0 0  0 -1 -1 2 1 1\np 3\n0 0 5\n1 0 5\n0 1 5\n", "snippet", s);
  REQUIRE(s.NumPrims() == 3);
  CHECK((s.prims[1].kind == PrimKind::kShape && s.prims[1].type == CR_PRIM_QUADRIC));
  REQUIRE(s.quadrics.size() == 1);
  const Quadric& q = s.quadrics[0];
  // (x - 1)^2 + y^2 + z^2 - 1 about the box's centre (1, 0, 0): Q = I, l = 0,
  // j = -1, each scaled by the same power of two.
  CHECK(q.center[0] == 1.0f);
  CHECK(q.extent[0] == 1.0f);
  CHECK(q.q[0] == q.q[1]);
  CHECK(q.q[3] == 0.0f);
  CHECK(q.l[0] == 0.0f);
  CHECK(q.j == -q.q[0]);
  CHECK(std::exp2(std::round(std::log2(q.q[0]))) == q.q[0]);
  // Quadrics come last in the unified order.
  CHECK(s.UnifiedIds() == std::vector<std::uint32_t>{0, 2, 1});
  const Bounds b = s.UnifiedBounds(2);
  CHECK(b.lo == glm::vec3(0, -1, -1));
  CHECK(b.hi == glm::vec3(2, 1, 1));

  test::CheckNffError("s 0 0 0 1\nquadric 1 1 1 0 0 0 0 0 0 -1 -1 -1 -1 1 1 1 1\n", ":2: unknown statement '1'");
  test::CheckNffError("quadric 1 1 1 0 0 0 0 0 0 -1 -1 -1 -1 1 1\n", ":1: truncated 'quadric' statement");
  test::CheckNffError("quadric 1 1 1 0 0 0 0 0 0 -1 -1 1 -1 1 1 1\n", ":1: 'quadric': clip box ymin 1 is not less than ymax 1");
  test::CheckNffError("quadric 0 0 0 0 0 0 0 0 0 -1 -1 -1 -1 1 1 1\n", ":1: 'quadric': coefficients A to I are all 0");
  test::CheckNffError("quadric 1 1 1 0 0 0 0 0 0 nan -1 -1 -1 1 1 1\n", "not a finite number");
}

TEST_CASE("quadric: every family, every structure x CPU backend x precision against the fp64 reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/quadrics.nff"));
  REQUIRE(scene.quadrics.size() == 8);
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast})
      test::CheckConformance(scene, "quadrics", backend, p, 40);
}

TEST_CASE("quadric: a ground ellipsoid 2e6 across, a tiny far one, rays leaving them: robust and fp64 0 wrong")
{
  Scene scene;
  ParseNFF(kHardScene, "hard-quadrics", scene);
  const auto aimed = AimedRays();
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast}) {
      test::CheckConformance(scene, "hard", backend, p, 48);
      for (AccelKind accel : kAccelKinds) {
        TraceConfig cfg;
        cfg.backend = backend;
        cfg.accel = accel;
        cfg.precision = p;
        const auto r = test::CheckTracer(scene, cfg, aimed, false);
        INFO("aimed at the tiny ellipsoid: ", BackendName(backend), " ", AccelKindName(accel), " ",
             PrecisionName(p), ": ", r.wrong, " wrong of ", r.rays);
        if (p != Precision::Fast) CHECK(r.wrong == 0);
      }
    }
  // The ground's primary hits: t within 1e-6 of the reference's in robust.
  const auto rays = test::MakeRays(scene, RayKind::Primary, 48);
  TraceConfig cfg;
  cfg.backend = Backend::Simd;
  const auto r = test::CheckTracer(scene, cfg, rays, false);
  MESSAGE("ground and bowl primary hits, SIMD robust: max relative t error ", r.maxRelTErr, ", mean ", r.meanRelTErr);
  CHECK(r.maxRelTErr <= 1e-6);
}

TEST_CASE("quadric: SIMD answers equal the scalar kernels' bit for bit (robust and fast, single and packet)")
{
  Scene hard;
  ParseNFF(kHardScene, "hard-quadrics", hard);
  const Scene& fam = test::CachedScene(test::SourcePath("scenes/geometry/quadrics.nff"));
  test::CheckSimdEqualsScalar(fam, 48);
  test::CheckSimdEqualsScalar(hard, 48);
}

TEST_CASE("quadric: OpenCL, every structure, robust and fp64 against the reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/quadrics.nff"));
  Scene hard;
  ParseNFF(kHardScene, "hard-quadrics", hard);
  test::CheckOpenCLConformance({{"quadrics", &scene}, {"hard", &hard}}, 24);
}
