// The convex polyhedron (NFF extension `polyhedron`, docs/FORMATS.md): its
// statement and stored form, and conformance against the fp64 reference on
// every structure, backend and precision, on the crystal field
// (scenes/geometry/polyhedra.nff) and on hard cases: rays in the planes of
// faces, through edges and vertices, and crystals 1e6 from the origin seen
// from nearby.
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include "host/core/error.h"
#include "tests/test_util.h"

using namespace cr;

namespace {


// A cube [-1, 1]^3 as six planes.
const char* kCube = "polyhedron 6\n1 0 0 -1\n-1 0 0 -1\n0 1 0 -1\n0 -1 0 -1\n0 0 1 -1\n0 0 -1 -1\n";

// The hard scene: the cube and an octahedron near the origin, the same
// octahedron and a thin tilted slab 1e6 away in front of a camera 12 from
// them, and a small triangle.
std::string HardScene()
{
  std::string s =
      "v\nfrom 1000000 4 999988\nat 1000000 0 1000000\nup 0 1 0\nangle 40\nhither 0.01\nresolution 64 64\n"
      "b 0.2 0.2 0.3\nl 1000010 100 999950\nf 0.8 0.8 0.8 0.8 0 10 0 1\n";
  s += kCube;
  // |x| + |y| + |z| <= 1.5 about (4, 0, 0) and about (1e6, 0, 1e6).
  for (const char* c : {"4 0 0", "1000000 0 1000000"}) {
    double cx, cy, cz;
    std::sscanf(c, "%lf %lf %lf", &cx, &cy, &cz);
    s += "polyhedron 8\n";
    for (int k = 0; k < 8; ++k) {
      const double a = k & 1 ? -1 : 1, b = k & 2 ? -1 : 1, cc = k & 4 ? -1 : 1;
      s += fmt::format("{} {} {} {}\n", a, b, cc, -(a * cx + b * cy + cc * cz) - 1.5);
    }
  }
  // A thin slab 1e6 away, tilted about z: 0.02 thick, 6 high and deep.
  s += "polyhedron 6\n0.6 0.8 0 -600000.61\n-0.6 -0.8 0 600000.59\n0 1 0 -3\n0 -1 0 -3\n0 0 1 -1000003\n"
       "0 0 -1 999997\n";
  s += "p 3\n-8 0 -6\n-6 0 -6\n-7 1.5 -6\n";
  return s;
}

// Rays in the cube's face planes and along its edges (they miss: a ray
// lying in a face's plane misses, as for the box), through its edges and
// vertices diagonally, and grazing them by one float step either side.
std::vector<RayRecord> FaceEdgeRays()
{
  std::vector<RayRecord> rays;
  auto add = [&](float ox, float oy, float oz, float dx, float dy, float dz) {
    RayRecord r{};
    r.org[0] = ox;
    r.org[1] = oy;
    r.org[2] = oz;
    r.dir[0] = dx;
    r.dir[1] = dy;
    r.dir[2] = dz;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    rays.push_back(r);
  };
  for (float off : {-0.5f, 0.0f, 0.5f, 1.0f})
    for (float eps : {0.0f, 1.0f, -1.0f}) {
      const float y = eps == 0.0f ? 1.0f : std::nextafter(1.0f, eps > 0 ? 2.0f : 0.0f);
      add(-5.0f, y, off, 1.0f, 0.0f, 0.0f);      // in (or just off) the top face's plane
      add(-5.0f, y, y, 1.0f, 0.0f, 0.0f);        // along an edge
      add(-3.0f, 2.0f + (y - 1.0f), off, 1.0f, -1.0f, 0.0f);  // through the edge x = -1, y = 1
      add(-4.0f, 4.0f, -4.0f + (y - 1.0f), 1.0f, -1.0f, 1.0f); // through a vertex
      add(off, 5.0f, y, 0.0f, -1.0f, 0.0f);      // down the face z = 1
    }
  return rays;
}

}  // namespace

TEST_CASE("polyhedron statement (extension): planes about the centre, ids in file order, bounds, errors")
{
  Scene s;
  ParseNFF(std::string("s 0 0 5 1\n") + kCube + "p 3\n0 0 5\n1 0 5\n0 1 5\n", "snippet", s);
  REQUIRE(s.NumPrims() == 3);
  CHECK((s.prims[1].kind == PrimKind::kShape && s.prims[1].type == CR_PRIM_POLYHEDRON));
  REQUIRE(s.polyhedra.size() == 1);
  const Polyhedron& p = s.polyhedra[0];
  CHECK(p.count == 6);
  CHECK(p.center[0] == 0.0f);
  CHECK(p.plane[0][0] == 1.0f);
  CHECK(p.plane[0][3] == -1.0f);
  // Polyhedra come last in the unified order; bounds hold the cube, padded
  // by a few millionths.
  CHECK(s.UnifiedIds() == std::vector<std::uint32_t>{0, 2, 1});
  const Bounds b = s.UnifiedBounds(2);
  for (int a = 0; a < 3; ++a) {
    CHECK((b.lo[a] <= -1.0f && b.lo[a] > -1.00001f));
    CHECK((b.hi[a] >= 1.0f && b.hi[a] < 1.00001f));
  }
  // A ray down the z axis enters at z = -1 (t = 4) on every backend.
  const std::vector<RayRecord> down = {RayRecord{{0.25f, 0.5f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY}};
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision prec : {Precision::Robust, Precision::Fp64, Precision::Fast}) {
      TraceConfig cfg;
      cfg.backend = backend;
      cfg.precision = prec;
      std::vector<HitRecord> hits;
      CreateTracer(s, cfg)->Trace(down, hits, false, nullptr);
      REQUIRE(hits.size() == 1);
      CHECK(hits[0].prim == 1);
      CHECK(hits[0].t == 4.0f);
    }

  test::CheckNffError("polyhedron 3\n1 0 0 -1\n-1 0 0 -1\n0 1 0 -1\n", ":1: 'polyhedron': 3 planes (a bounded solid needs 4 to 32)");
  test::CheckNffError("polyhedron 33\n", ":1: 'polyhedron': 33 planes");
  test::CheckNffError("polyhedron 5\n1 0 0 -1\n-1 0 0 -1\n0 1 0 -1\n0 -1 0 -1\n0 0 1 -1\n", "unbounded");
  test::CheckNffError("polyhedron 6\n1 0 0 1\n-1 0 0 -1\n0 1 0 -1\n0 -1 0 -1\n0 0 1 -1\n0 0 -1 -1\n", "enclose no solid");
  test::CheckNffError("polyhedron 6\n1 0 0 -1\n-1 0 0 1\n0 1 0 -1\n0 -1 0 -1\n0 0 1 -1\n0 0 -1 -1\n", "enclose no solid");
  test::CheckNffError("polyhedron 4\n0 0 0 -1\n-1 0 0 -1\n0 1 0 -1\n0 -1 0 -1\n", "plane 1 (0 0 0 -1) has no direction");
  test::CheckNffError("polyhedron 6\n1 0 0 -1\n-1 0 0 -1\n", ":3: truncated 'polyhedron' statement");
  test::CheckNffError("polyhedron 4\n1 0 0 nan\n", "not a finite number");
}

TEST_CASE("polyhedron: the crystal field, every structure x CPU backend x precision against the fp64 reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/polyhedra.nff"));
  REQUIRE(scene.polyhedra.size() == 28);
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast})
      test::CheckConformance(scene, "polyhedra", backend, p, 40);
}

TEST_CASE("polyhedron: faces, edges and vertices, crystals 1e6 away seen from 12: robust and fp64 0 wrong")
{
  Scene scene;
  ParseNFF(HardScene(), "hard-polyhedra", scene);
  const auto along = FaceEdgeRays();
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (Precision p : {Precision::Robust, Precision::Fp64, Precision::Fast}) {
      test::CheckConformance(scene, "hard", backend, p, 48);
      for (AccelKind accel : kAccelKinds) {
        TraceConfig cfg;
        cfg.backend = backend;
        cfg.accel = accel;
        cfg.precision = p;
        const auto r = test::CheckTracer(scene, cfg, along, false);
        INFO("faces, edges, vertices: ", BackendName(backend), " ", AccelKindName(accel), " ", PrecisionName(p), ": ",
             r.wrong, " wrong of ", r.rays);
        if (p != Precision::Fast) CHECK(r.wrong == 0);
      }
    }
  // The far crystals' primary hits: t within 1e-6 of the reference's.
  const auto rays = test::MakeRays(scene, RayKind::Primary, 48);
  TraceConfig cfg;
  cfg.backend = Backend::Simd;
  const auto r = test::CheckTracer(scene, cfg, rays, false);
  MESSAGE("far crystals' primary hits, SIMD robust: max relative t error ", r.maxRelTErr, ", mean ", r.meanRelTErr);
  CHECK(r.maxRelTErr <= 1e-6);
}

TEST_CASE("polyhedron: SIMD answers equal the scalar kernels' bit for bit (robust and fast, single and packet)")
{
  Scene hard;
  ParseNFF(HardScene(), "hard-polyhedra", hard);
  const Scene& field = test::CachedScene(test::SourcePath("scenes/geometry/polyhedra.nff"));
  test::CheckSimdEqualsScalar(field, 48);
  test::CheckSimdEqualsScalar(hard, 48);
}

TEST_CASE("polyhedron: OpenCL, every structure, robust and fp64 against the reference")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/geometry/polyhedra.nff"));
  Scene hard;
  ParseNFF(HardScene(), "hard-polyhedra", hard);
  test::CheckOpenCLConformance({{"polyhedra", &scene}, {"hard", &hard}}, 24);
}
