// The CSG solid (NFF extension `csg union|intersection|difference` ...
// `csg end`, docs/FORMATS.md): its statement, leaf ids and errors, the
// classification on closed forms (which leaf a hit names, its normal's
// side, coincident faces), and conformance against the fp64 reference on
// every structure, backend and precision on scenes/geometry/csg.nff (a die,
// a lens, a cut ellipsoid, a hollow polyhedron, nested unions).
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/reference/check.h"
#include "host/reference/reference.h"
#include "host/scene/surface.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

// A die: the box [-1, 1]^3 minus a sphere of radius 0.5 about (1, 0, 0).
const char* kBite =
    "s 0 0 9 1\n"
    "csg difference\n  box -1 -1 -1 1 1 1\n  f 1 0 0 1 0 0 0 1\n  s 1 0 0 0.5\ncsg end\n"
    "s 0 0 -9 1\n";

std::vector<HitRecord> TraceCsg(const Scene& s, const std::vector<RayRecord>& rays, Backend b, Precision p,
                             bool occlusion = false, bool unified = false)
{
  TraceConfig cfg;
  cfg.backend = b;
  cfg.precision = p;
  cfg.unifiedHits = unified;
  std::vector<HitRecord> hits;
  CreateTracer(s, cfg)->Trace(rays, hits, occlusion, nullptr);
  return hits;
}

std::vector<Backend> CpuBackends() { return {Backend::Scalar, Backend::Simd}; }

}  // namespace

TEST_CASE("csg statement (extension): one id per leaf in file order, one record per block, materials, errors")
{
  Scene s;
  ParseNFF(kBite, "bite", s);
  REQUIRE(s.NumPrims() == 4);
  REQUIRE(s.csgs.size() == 1);
  const Csg& c = s.csgs[0];
  CHECK(c.nLeaves == 2);
  CHECK(c.nNodes == 3);
  CHECK((s.prims[1].type == CR_PRIM_CSG && s.prims[1].part == 0 && s.prims[2].part == 1));
  CHECK(s.prims[1].firstPiece == s.prims[2].firstPiece);
  CHECK(s.prims[2].material != s.prims[1].material);  // the `f` inside the block
  CHECK(s.prims[3].material == s.prims[1].material);  // ... ends with it
  CHECK(s.UnifiedIds() == std::vector<std::uint32_t>{0, 3, 1});
  CHECK(c.lo[0] == -1.0f);
  CHECK(c.hi[0] == 1.0f);  // a difference keeps its first operand's box

  // Along the x axis from -5: the box's face x = -1 (leaf 0, id 1) at t = 4.
  // At y = 0, from +5 down the x axis: the bite's floor, the sphere (leaf 1,
  // id 2) at x = 0.5, t = 4.5, its normal turned to face +x. At y = 0.9:
  // the box face x = 1 at t = 4.
  const std::vector<RayRecord> rays = {RayRecord{{-5.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY},
                                       RayRecord{{5.0f, 0.0f, 0.0f}, 0.0f, {-1.0f, 0.0f, 0.0f}, INFINITY},
                                       RayRecord{{5.0f, 0.9f, 0.0f}, 0.0f, {-1.0f, 0.0f, 0.0f}, INFINITY},
                                       RayRecord{{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY}};
  for (Backend b : CpuBackends())
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast}) {
      INFO(BackendName(b), " ", PrecisionName(p));
      const auto h = TraceCsg(s, rays, b, p);
      CHECK(h[0].prim == 1);
      CHECK(h[0].t == doctest::Approx(4.0));
      CHECK(h[1].prim == 2);
      CHECK(h[1].t == doctest::Approx(4.5));
      CHECK(h[2].prim == 1);
      CHECK(h[2].t == doctest::Approx(4.0));
      // From inside the solid: leaves it through the sphere at x = 0.5.
      CHECK(h[3].prim == 2);
      CHECK(h[3].t == doctest::Approx(0.5));
      // The renderer's form names the piece and carries the leaf and its
      // side; the surface's normal points out of the solid (+x at the bite).
      const auto u = TraceCsg(s, rays, b, p, false, true);
      REQUIRE(u[1].prim == s.Ranges().begin[CR_PRIM_CSG]);
      CHECK(u[1].u == 1.0f);
      CHECK(u[1].v == 1.0f);
      CHECK(s.IdOfHit(u[1].prim, u[1].u) == 2u);
      const SurfacePoint sp = SurfaceAt(s, u[1].prim, glm::dvec3(0.5, 0.0, 0.0), u[1].u, u[1].v);
      CHECK(sp.ng.x == doctest::Approx(1.0));
      CHECK(u[0].v == 0.0f);
      // Occlusion names the leaf of the first crossing.
      const auto o = TraceCsg(s, rays, b, p, true);
      CHECK(o[1].prim == 2);
      CHECK(o[1].t == 0.0f);
    }

  test::CheckNffError("csg union\n  s 0 0 0 1\n", ":2: truncated 'csg' block");
  test::CheckNffError("csg union\ncsg end\n", ":1: 'csg' block (line 1) has no operand");
  test::CheckNffError("csg union\n  c 0 0 0 1 0 1 0 1\ncsg end\n", ":2: 'csg': 'c' is not a closed solid");
  test::CheckNffError("csg union\n  p 3 0 0 0 1 0 0 0 1 0\ncsg end\n", ":2: 'csg': 'p' is not a closed solid");
  test::CheckNffError("csg union\n  s 0 0 0 -1\ncsg end\n", ":2: 'csg': a sphere of radius 0 or below");
  test::CheckNffError("csg union\n  box 0 0 0 1 0 1\ncsg end\n", ":2: 'csg': a flat box");
  test::CheckNffError("csg union\n  quadric 1 1 0 0 0 0 0 0 0 -1 -2 -2 -2 2 2 2\ncsg end\n",
                      ":2: 'csg': the quadric is not a closed solid");
  test::CheckNffError("csg union\n  quadric 1 1 1 0 0 0 0 0 0 -1 -0.5 -2 -2 2 2 2\ncsg end\n",
                      ":2: 'csg': the quadric is not a closed solid");
  test::CheckNffError("csg xor\n  s 0 0 0 1\ncsg end\n", ":1: 'csg': expected union, intersection, difference");
  test::CheckNffError("csg end\n", ":1: 'csg end' without an open 'csg' block");
  test::CheckNffError("csg intersection\n  s 0 0 0 1\n  s 5 0 0 1\ncsg end\n", ":1: 'csg': the solid is empty");
  test::CheckNffError("csg union\n  sdf 0 0 0 1 1 1 0.001 64 1.5\n  sphere 0 0 0 1\n  sdf end\ncsg end\n",
                      ":2: 'csg': 'sdf' is not a closed solid");
  std::string many = "csg union\n";
  for (int k = 0; k < 33; ++k) many += fmt::format("  s {} 0 0 1\n", k);
  test::CheckNffError(many + "csg end\n", ":34: 'csg': more than 32 leaves in one block");
  std::string heavy = "csg union\n";
  for (int k = 0; k < 17; ++k) heavy += "  quadric 1 1 1 0 0 0 0 0 0 -1 -2 -2 -2 2 2 2\n";
  test::CheckNffError(heavy + "csg end\n", ":18: 'csg': the block's leaves need more than 64 words");
}

TEST_CASE("csg: coincident faces, nesting and every operand kind on closed forms")
{
  // Two unit cubes sharing the face x = 1 in a union: no surface there. The
  // same cubes' intersection with a sphere, a flush difference (the cut is
  // the box's own face), an ellipsoid and an octahedron.
  Scene s;
  ParseNFF("csg union\n  box 0 0 0 1 1 1\n  box 1 0 0 2 1 1\ncsg end\n"                          // ids 0, 1
           "csg difference\n  box 0 3 0 2 4 1\n  box 1 3 0 2 4 1\ncsg end\n"                       // ids 2, 3
           "csg intersection\n  csg union\n    box 0 6 0 1 7 1\n    box 1 6 0 2 7 1\n  csg end\n"  // ids 4, 5
           "  s 1 6.5 0.5 0.8\ncsg end\n"                                                            // id 6
           "csg difference\n  quadric 1 4 1 0 0 0 0 -72 0 321.75 -2 8 -2 2 10 2\n"                    // id 7
           "  polyhedron 8\n 1 1 1 -9.5\n -1 1 1 -9.5\n 1 -1 1 8.5\n -1 -1 1 8.5\n"               // id 8
           " 1 1 -1 -9.5\n -1 1 -1 -9.5\n 1 -1 -1 8.5\n -1 -1 -1 8.5\ncsg end\n",
           "closed-forms", s);
  REQUIRE(s.csgs.size() == 4);
  const std::vector<RayRecord> rays = {
      // Down the cubes' middle: enters at x = 0, leaves at x = 2 (no face at 1).
      RayRecord{{-1.0f, 0.5f, 0.5f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY},
      RayRecord{{0.5f, 0.5f, 0.5f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY},
      // The flush difference leaves [0, 1]: from x = 3 back, its face x = 1
      // (the subtrahend's face, turned).
      RayRecord{{3.0f, 3.5f, 0.5f}, 0.0f, {-1.0f, 0.0f, 0.0f}, INFINITY},
      // Nested union intersected with the sphere: the sphere bounds it at
      // x = 1 - 0.8 along its centre line.
      RayRecord{{-1.0f, 6.5f, 0.5f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY},
      // The ellipsoid x^2 + 4 (y - 9)^2 + z^2 = 2.25 minus the octahedron
      // |x| + |y - 9| + |z| <= 0.5 (written as planes): down the y axis from
      // above the top (y = 9.75) through the hollow: ellipsoid at 9.75, the
      // octahedron's top vertex at 9.5.
      RayRecord{{0.0f, 12.0f, 0.001f}, 0.0f, {0.0f, -1.0f, 0.0f}, INFINITY},
      RayRecord{{0.0f, 9.6f, 0.001f}, 0.0f, {0.0f, -1.0f, 0.0f}, INFINITY},
  };
  for (Backend b : CpuBackends())
    for (Precision p : {Precision::Robust, Precision::Fp64}) {
      INFO(BackendName(b), " ", PrecisionName(p));
      const auto h = TraceCsg(s, rays, b, p);
      CHECK(h[0].prim == 0);
      CHECK(h[0].t == 1.0f);
      CHECK(h[1].prim == 1);
      CHECK(h[1].t == 1.5f);
      CHECK(h[2].prim == 3);
      CHECK(h[2].t == 2.0f);
      CHECK(h[3].prim == 6);
      CHECK(h[3].t == doctest::Approx(1.2));
      CHECK(h[4].prim == 7);
      CHECK(h[4].t == doctest::Approx(2.25));
      CHECK(h[5].prim == 8);
      CHECK(h[5].t == doctest::Approx(0.101).epsilon(1e-3));
    }
  // check judges a leaf by its part of the solid: the shared face of the
  // union (x = 1) and the flush cut's hidden face (x = 2) are no surface,
  // named by either leaf; a leaf that does not bound the solid at the
  // point is wrong too; the true answers agree.
  {
    Scene one;
    ParseNFF("csg union\n  box 0 0 0 1 1 1\n  box 1 0 0 2 1 1\ncsg end\n"
             "csg difference\n  box 0 3 0 2 4 1\n  box 1 3 0 2 4 1\ncsg end\n",
             "judged", one);
    const ref::ReferenceTracer tr(one);
    const RayRecord across{{-1.0f, 0.5f, 0.5f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY};
    const RayRecord back{{3.0f, 3.5f, 0.5f}, 0.0f, {-1.0f, 0.0f, 0.0f}, INFINITY};
    auto wrong = [&](const RayRecord& r, float t, std::uint32_t prim) {
      return ref::CheckHits(tr, {r}, {HitRecord{t, prim, 0.0f, 0.0f}}, false).wrong;
    };
    CHECK(wrong(across, 1.0f, 0) == 0);
    CHECK(wrong(across, 2.0f, 0) == 1);
    CHECK(wrong(across, 2.0f, 1) == 1);
    CHECK(wrong(across, 1.0f, 1) == 1);  // box 1 does not bound the solid at x = 0
    CHECK(wrong(back, 2.0f, 3) == 0);
    CHECK(wrong(back, 1.0f, 2) == 1);
    CHECK(wrong(back, 1.0f, 3) == 1);
    CHECK(wrong(back, 2.0f, 2) == 1);  // the cut face is the subtrahend's
  }
  // The reference agrees ray by ray.
  for (RayKind kind : {RayKind::Primary, RayKind::Random}) {
    const auto many = test::MakeRays(s, kind, 32);
    TraceConfig cfg;
    const auto r = test::CheckTracer(s, cfg, many, false);
    CHECK(r.wrong == 0);
  }
}

TEST_CASE("csg: the CSG scene, every structure x CPU backend x precision against the fp64 reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/csg.nff"));
  REQUIRE(scene.csgs.size() == 5);
  for (Backend backend : CpuBackends())
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast})
      test::CheckConformance(scene, "csg", backend, p, 32);
}

TEST_CASE("csg: SIMD answers equal the scalar kernels' bit for bit (robust, single and packet)")
{
  // Robust only: the SIMD units test a CSG solid's leaves with the robust
  // tests in every mode (simd/csg.h).
  test::CheckSimdEqualsScalar(test::CachedScene(test::SourcePath("scenes/geometry/csg.nff")), 32, false);
}

TEST_CASE("csg: OpenCL, every structure, robust and fp64 against the reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/csg.nff"));
  test::CheckOpenCLConformance({{"csg", &scene}}, 24);
}
