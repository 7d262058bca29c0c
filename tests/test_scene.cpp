// Scene loading: SPD primitive counts, NFF statements, triangulation.
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/scene/generate.h"
#include "host/scene/triangulate.h"
#include "tests/test_util.h"

using namespace cr;
using namespace cr::test;

namespace {

struct SpdCounts {
  const char* name;
  std::uint32_t spheres, cones, polygons, patches, lights;
};

// Statement counts of the SPD scenes at their default size (../shared/SPD.md).
const SpdCounts kSpd[] = {
    {"balls", 7381, 0, 1, 0, 3},    {"gears", 0, 0, 9345, 0, 5},   {"jacks", 6, 3, 0, 0, 1},
    {"lattice", 2197, 6084, 0, 0, 6}, {"mount", 4, 0, 8192, 0, 1}, {"rings", 4200, 4200, 1, 0, 3},
    {"shells", 5761, 0, 0, 0, 1},   {"sombrero", 0, 0, 1922, 0, 1}, {"teapot", 0, 0, 36, 2256, 2},
    {"tetra", 0, 0, 4096, 0, 1},    {"tree", 4095, 4095, 1, 0, 7},
};

double PolygonArea(const Scene& s, std::uint32_t id)
{
  const PrimInfo& p = s.prims[id];
  double a = 0.0;
  for (std::uint32_t i = 0; i < p.nPieces; ++i) {
    const Triangle& t = s.triangles[p.firstPiece + i];
    glm::dvec3 v0(t.v0[0], t.v0[1], t.v0[2]), v1(t.v1[0], t.v1[1], t.v1[2]), v2(t.v2[0], t.v2[1], t.v2[2]);
    a += 0.5 * glm::length(glm::cross(v1 - v0, v2 - v0));
  }
  return a;
}

}  // namespace

TEST_CASE("SPD scenes load with the published primitive counts")
{
  for (const SpdCounts& c : kSpd) {
    const Scene& s = test::CachedScene(test::SpdPath(c.name));
    INFO(c.name);
    CHECK(s.CountKind(PrimKind::kShape, CR_PRIM_SPHERE) == c.spheres);
    CHECK(s.CountKind(PrimKind::kShape, CR_PRIM_CONE) == c.cones);
    CHECK(s.CountKind(PrimKind::kPolygon, CR_PRIM_TRIANGLE) == c.polygons);
    CHECK(s.CountKind(PrimKind::kPatch, CR_PRIM_TRIANGLE) == c.patches);
    CHECK(s.lights.size() == c.lights);
    CHECK(s.NumPrims() == c.spheres + c.cones + c.polygons + c.patches);
    // No SPD primitive is degenerate: every statement has geometry.
    CHECK(s.spheres.size() == c.spheres);
    CHECK(s.cones.size() == c.cones);
    CHECK(s.hasCamera);
    // Ids are statement positions: unified index -> id is a bijection onto
    // the geometric statements.
    std::vector<int> seen(s.NumPrims(), 0);
    for (std::uint32_t id : s.UnifiedIds()) seen.at(id) = 1;
    CHECK(std::count(seen.begin(), seen.end(), 1) == int(s.NumPrims()));
  }
}

TEST_CASE("gears: the non-convex 144-vertex faces triangulate without losing or adding area")
{
  const Scene& s = test::CachedScene(test::SpdPath("gears"));
  int big = 0;
  for (const PrimInfo& p : s.prims) {
    if (p.nPieces < 100) continue;
    ++big;
    CHECK(p.nPieces == 142);  // a simple 144-gon splits into n - 2 triangles
  }
  CHECK(big > 0);

  // The first 144-vertex face of the file, alone: its pieces cover exactly
  // the polygon's (Newell) area.
  std::vector<char> data = ReadFile(test::SpdPath("gears"));
  std::string_view text(data.data(), data.size());
  std::size_t at = text.find("\np 144\n");
  REQUIRE(at != std::string_view::npos);
  std::size_t end = at + 1;
  for (int line = 0; line < 145; ++line) end = text.find('\n', end) + 1;
  std::string face(text.substr(at + 1, end - at - 1));
  Scene one;
  ParseNFF(face, "gears-face", one);
  REQUIRE(one.NumPrims() == 1);
  std::vector<glm::dvec3> verts;
  std::size_t p = face.find('\n') + 1;
  double x, y, z;
  while (p < face.size() && std::sscanf(face.c_str() + p, "%lf %lf %lf", &x, &y, &z) == 3) {
    verts.emplace_back(float(x), float(y), float(z));
    p = face.find('\n', p) + 1;
  }
  REQUIRE(verts.size() == 144);
  Triangulation tri = TriangulatePolygon(verts);
  CHECK_FALSE(tri.nonSimple);
  CHECK(PolygonArea(one, 0) == doctest::Approx(tri.area).epsilon(1e-6));
}

TEST_CASE("triangulation: convex, non-convex, collinear and repeated vertices")
{
  using V = glm::dvec3;
  SUBCASE("triangle keeps its order")
  {
    auto t = TriangulatePolygon({V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)});
    REQUIRE(t.triangles.size() == 1);
    CHECK(t.triangles[0] == std::array<std::uint32_t, 3>{0, 1, 2});
  }
  SUBCASE("L shape (non-convex) splits into 4 triangles of total area 3")
  {
    std::vector<V> l = {V(0, 0, 0), V(2, 0, 0), V(2, 1, 0), V(1, 1, 0), V(1, 2, 0), V(0, 2, 0)};
    auto t = TriangulatePolygon(l);
    CHECK(t.triangles.size() == 4);
    CHECK_FALSE(t.nonSimple);
    double a = 0;
    for (auto& tr : t.triangles) a += 0.5 * glm::length(glm::cross(l[tr[1]] - l[tr[0]], l[tr[2]] - l[tr[0]]));
    CHECK(a == doctest::Approx(3.0));
    CHECK(t.area == doctest::Approx(3.0));
  }
  SUBCASE("clockwise polygon in a tilted plane")
  {
    std::vector<V> q = {V(0, 0, 0), V(0, 1, 1), V(1, 1, 1), V(1, 0, 0)};
    auto t = TriangulatePolygon(q);
    CHECK(t.triangles.size() == 2);
    CHECK(t.area == doctest::Approx(std::sqrt(2.0)));
  }
  SUBCASE("collinear and repeated vertices are dropped")
  {
    std::vector<V> q = {V(0, 0, 0), V(1, 0, 0), V(1, 0, 0), V(2, 0, 0), V(2, 2, 0), V(0, 2, 0), V(0, 0, 0)};
    auto t = TriangulatePolygon(q);
    CHECK_FALSE(t.degenerate);
    CHECK(t.triangles.size() <= 3);
    double a = 0;
    for (auto& tr : t.triangles) {
      double ta = 0.5 * glm::length(glm::cross(q[tr[1]] - q[tr[0]], q[tr[2]] - q[tr[0]]));
      CHECK(ta > 0.0);  // no zero-area sliver from the collinear vertex
      a += ta;
    }
    CHECK(a == doctest::Approx(4.0));
  }
  SUBCASE("zero area and too few vertices are degenerate")
  {
    CHECK(TriangulatePolygon({V(0, 0, 0), V(1, 1, 1), V(2, 2, 2)}).degenerate);
    CHECK(TriangulatePolygon({V(0, 0, 0), V(1, 1, 1)}).degenerate);
    CHECK(TriangulatePolygon({V(0, 0, 0), V(0, 0, 0), V(0, 0, 0), V(0, 0, 0)}).degenerate);
  }
}

TEST_CASE("NFF statements: lights with colour, cones, negative radii, patches, ids")
{
  const char* text =
      "b 0.1 0.2 0.3\n"
      "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 40\nhither 0.5\nresolution 64 32\n"
      "l 1 2 3\n"
      "l 4 5 6 0.5 0.25 1\n"
      "# a comment line\n"
      "f 1 0 0 0.8 0.2 10 0 1 # trailing comment\n"
      "s 0 0 0 -1\n"
      "c 0 0 0 0.5\n  0 0 2 0.25\n"
      "p 2\n0 0 0\n1 0 0\n"
      "pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
      "s 1 1 1 0\n"
      "p 4\n0 0 5\n1 0 5\n1 1 5\n0 1 5\n";
  Scene s;
  SetWarningsQuiet(true);
  long before = WarningCount();
  ParseNFF(text, "snippet", s);
  long warned = WarningCount() - before;
  SetWarningsQuiet(false);
  CHECK(warned == 2);  // the 2-vertex polygon and the zero-radius sphere
  CHECK(s.background == glm::vec3(0.1f, 0.2f, 0.3f));
  CHECK(s.camera.width == 64);
  CHECK(s.camera.height == 32);
  CHECK(s.camera.hither == 0.5f);
  REQUIRE(s.lights.size() == 2);
  CHECK(s.lights[0].color == glm::vec3(1.0f));
  CHECK(s.lights[1].color == glm::vec3(0.5f, 0.25f, 1.0f));
  REQUIRE(s.NumPrims() == 6);
  CHECK((s.prims[0].kind == PrimKind::kShape && s.prims[0].type == CR_PRIM_SPHERE));
  CHECK(s.prims[0].insideVisible);
  CHECK(s.spheres[0].radius == 1.0f);
  CHECK((s.prims[1].kind == PrimKind::kShape && s.prims[1].type == CR_PRIM_CONE));
  CHECK(s.cones[0].apexRadius == 0.25f);
  CHECK(s.prims[2].nPieces == 0);  // degenerate polygon keeps id 2
  CHECK(s.prims[3].kind == PrimKind::kPatch);
  CHECK(s.prims[4].nPieces == 0);  // zero-radius sphere keeps id 4
  CHECK(s.prims[5].nPieces == 2);
  CHECK(s.pieceIds[CR_PRIM_TRIANGLE] == std::vector<std::uint32_t>{3, 5, 5});
  CHECK(s.pieceIds[CR_PRIM_SPHERE] == std::vector<std::uint32_t>{0});
  CHECK(s.pieceIds[CR_PRIM_CONE] == std::vector<std::uint32_t>{1});
  REQUIRE(s.HasPatchNormals());
  CHECK(s.triNormals[0][0] == glm::vec3(0, 0, 1));
  // The patch has a vertex at the origin: its two edges from there are long
  // (longer than 16 times their distance from the origin, TriangleEdgeFlags);
  // the quad at z = 5 has none.
  CHECK(s.triangles[0].flags == (CR_TRI_REPORT_UV | CR_TRI_LONG_V | CR_TRI_LONG_W));
  CHECK(s.triangles[1].flags == 0u);
  CHECK(s.materials.size() == 2);
  CHECK(s.prims[0].material == 1);
}

TEST_CASE("SPD camera: tetra corner rays hit 49,788 times (+-0.5%), every balls corner ray hits")
{
  for (const char* name : {"tetra", "balls"}) {
    const Scene& s = test::CachedScene(test::SpdPath(name));
    RayGenOptions g;
    g.spdCorners = true;
    auto rays = GenerateRays(s, test::CachedReference(s), g);
    REQUIRE(rays.size() == 263169u);
    TraceConfig cfg;
    cfg.backend = Backend::Reference;
    auto tracer = CreateTracer(s, cfg);
    std::vector<HitRecord> hits;
    tracer->Trace(rays, hits, false, nullptr);
    std::size_t n = std::count_if(hits.begin(), hits.end(), [](const HitRecord& h) { return h.prim != CR_NO_HIT; });
    INFO(name, ": ", n, " hits");
    if (std::string(name) == "tetra") {
      CHECK(double(n) >= 49788 * 0.995);
      CHECK(double(n) <= 49788 * 1.005);
    } else {
      CHECK(n == rays.size());
    }
  }
}

TEST_CASE("OBJ: lines end and comments stop where tinyobjloader sees them (found by fuzz_obj)")
{
  // A lone '\r' ends a line for tinyobjloader, and it knows no trailing
  // comments: before the fix, "f 1 2 3#x 99" reached it whole, it read a 4th
  // reference (99) that no check had seen, and the next face read vertex 99
  // out of bounds (ASan heap-buffer-overflow; tests/fuzz/corpus/obj/regress_*).
  const std::string dir = test::ProcessTempDir("cellray_obj").string();
  const std::string path = dir + "/lines.obj";
  const std::string text = "v -1 -1 0\rv 1 -1 0\r\nv 0 1 0\r"  // lines 1-3, three line ends
                           "f 1 2 3#x 99\n"                     // line 4: a comment from '#'
                           "v 0 0 5 # apex\n"                   // line 5
                           "f 1 2 4 # x 98\n";                   // line 6
  WriteFileAtomically(path, text.data(), text.size());
  SetWarningsQuiet(true);
  Scene s = LoadOBJ(path);
  SetWarningsQuiet(false);
  REQUIRE(s.NumPrims() == 2);
  CHECK(s.prims[0].line == 4u);
  CHECK(s.prims[1].line == 6u);
  REQUIRE(s.triangles.size() == 2);
  CHECK(s.triangles[0].v2[1] == 1.0f);
  CHECK(s.triangles[1].v2[2] == 5.0f);
  std::filesystem::remove_all(dir);
}

TEST_CASE("NFF box statement (extension): layout, ids among the other statements, unified order, bounds")
{
  const char* text =
      "s 0 0 0 1\n"
      "box -1 -2 -3 1 2 3\n"
      "p 3\n0 0 5\n1 0 5\n0 1 5\n"
      "box 2 2 2 2 3 4  # flat on x: a rectangle\n";
  Scene s;
  ParseNFF(text, "snippet", s);
  REQUIRE(s.NumPrims() == 4);
  CHECK((s.prims[1].kind == PrimKind::kShape && s.prims[1].type == CR_PRIM_BOX));
  REQUIRE(s.boxes.size() == 2);
  CHECK(s.boxes[0].lo[1] == -2.0f);
  CHECK(s.boxes[0].hi[2] == 3.0f);
  CHECK(s.boxes[1].lo[0] == s.boxes[1].hi[0]);
  CHECK(s.pieceIds[CR_PRIM_BOX] == std::vector<std::uint32_t>{1, 3});
  // Boxes come last in the unified order: sphere, triangle, then the boxes.
  CHECK(s.UnifiedIds() == std::vector<std::uint32_t>{0, 2, 1, 3});
  const Bounds b = s.UnifiedBounds(2);
  CHECK(b.lo == glm::vec3(-1, -2, -3));
  CHECK(b.hi == glm::vec3(1, 2, 3));
  CHECK(s.CountKind(PrimKind::kShape, CR_PRIM_BOX) == 2);
}

TEST_CASE("SubdivideMesh: exact triangle counts on the same surface (area, bounds, primary hits)")
{
  const Scene& tetra = CachedScene(SpdPath("tetra"));
  const std::uint64_t n0 = tetra.triangles.size();
  REQUIRE(n0 == 4096);
  const auto area = [](const Scene& s) {
    double a = 0.0;
    for (const Triangle& t : s.triangles) {
      const glm::dvec3 v0(t.v0[0], t.v0[1], t.v0[2]), v1(t.v1[0], t.v1[1], t.v1[2]), v2(t.v2[0], t.v2[1], t.v2[2]);
      a += 0.5 * glm::length(glm::cross(v1 - v0, v2 - v0));
    }
    return a;
  };
  const auto bounds = [](const Scene& s) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const Triangle& t : s.triangles)
      for (const float* v : {t.v0, t.v1, t.v2}) {
        lo = glm::min(lo, glm::vec3(v[0], v[1], v[2]));
        hi = glm::max(hi, glm::vec3(v[0], v[1], v[2]));
      }
    return std::make_pair(lo, hi);
  };
  const double a0 = area(tetra);
  TraceConfig config;
  config.backend = Backend::Scalar;
  const std::vector<RayRecord> rays = MakeRays(tetra, RayKind::Primary, 96);
  std::vector<HitRecord> h0;
  CreateTracer(tetra, config)->Trace(rays, h0, false, nullptr);
  for (const std::uint64_t n : {n0, 4 * n0, 4 * n0 + 777, 16 * n0 + 5}) {
    CAPTURE(n);
    const Scene s = SubdivideMesh(tetra, n);
    CHECK(s.triangles.size() == n);
    CHECK(s.NumPrims() == n);
    CHECK(std::abs(area(s) - a0) <= 1e-5 * a0);
    // Midpoints of float vertices, rounded to float, stay within them.
    CHECK(bounds(s) == bounds(tetra));
    CHECK(s.camera.from == tetra.camera.from);
    // The same surface: the same rays hit it, at the same distance.
    std::vector<HitRecord> h;
    CreateTracer(s, config)->Trace(rays, h, false, nullptr);
    REQUIRE(h.size() == h0.size());
    std::size_t status = 0, far = 0, hits = 0;
    for (std::size_t i = 0; i < h.size(); ++i) {
      const bool a = h0[i].prim != CR_NO_HIT, b = h[i].prim != CR_NO_HIT;
      status += a != b;
      hits += a;
      if (a && b) far += std::abs(h[i].t - h0[i].t) > 1e-5f * h0[i].t;
    }
    CHECK(hits > rays.size() / 8);
    CHECK(status <= rays.size() / 500);
    CHECK(far == 0);
  }
  CHECK_THROWS_AS(SubdivideMesh(tetra, n0 - 1), InputError);
  CHECK_THROWS_AS(SubdivideMesh(CachedScene(SpdPath("balls")), 100000), InputError);
}
