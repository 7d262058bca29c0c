// Uniform grid: builder invariants and named hard cases of the 3D-DDA
// (kernels/grid.h), each asserting the primitive id a ray must report. Every
// case runs with the robust (float) and fp64 kernels of the scalar backend.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <fmt/format.h>

#include "host/accel/accel.h"
#include "host/core/error.h"
#include "host/scene/scene.h"
#include "host/trace/tracer.h"
#include "tests/test_util.h"

namespace cr {
namespace test_grid {
// Grid_Plane(), the planes the traversal walks.
#include "kernels/grid.h"
}  // namespace test_grid
}  // namespace cr

using namespace cr;

namespace {

constexpr Precision kPrecisions[] = {Precision::Robust, Precision::Fp64};

Scene SceneFromNFF(const std::string& text)
{
  Scene s;
  ParseNFF(text, "test", s);
  return s;
}

std::string Sphere3(double x, double y, double z, double r) { return fmt::format("s {} {} {} {}\n", x, y, z, r); }

std::string Quad(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d)
{
  return fmt::format("p 4\n{} {} {}\n{} {} {}\n{} {} {}\n{} {} {}\n", a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x,
                     d.y, d.z);
}

std::string Tri(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c)
{
  return fmt::format("p 3\n{} {} {}\n{} {} {}\n{} {} {}\n", a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z);
}

RayRecord MakeRay(glm::vec3 o, glm::vec3 d, float tmin = 0.0f, float tmax = INFINITY)
{
  return RayRecord{{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

// A scene with its grid (for the planes) and one grid tracer per precision.
struct GridCase {
  Scene scene;
  GridData grid;
  std::unique_ptr<Tracer> tracers[2];

  GridCase(const std::string& nff, double density) : scene(SceneFromNFF(nff))
  {
    AccelParams p;
    p.gridDensity = density;
    AccelInfo info;
    grid = BuildGrid(scene, p, info);
    for (int i = 0; i < 2; ++i) {
      TraceConfig cfg;
      cfg.backend = Backend::Scalar;
      cfg.accel = AccelKind::Grid;
      cfg.precision = kPrecisions[i];
      cfg.params = p;
      tracers[i] = CreateTracer(scene, cfg);
    }
  }
  const GridHeader& H() const { return grid.header; }
  float Plane(int axis, int i) const { return test_grid::Grid_Plane(&grid.header, axis, i); }
  int Res(int axis) const { return int(grid.header.res[axis]); }

  // Primitive ids reported by each precision for `rays`.
  std::vector<std::uint32_t> Ids(const std::vector<RayRecord>& rays, int precision, bool occlusion = false) const
  {
    std::vector<HitRecord> hits;
    tracers[precision]->Trace(rays, hits, occlusion, nullptr);
    std::vector<std::uint32_t> ids;
    for (const HitRecord& h : hits) ids.push_back(h.prim);
    return ids;
  }
  // Checks the closest hit of every ray against `expected`, in both precisions.
  void Expect(const std::vector<RayRecord>& rays, const std::vector<std::uint32_t>& expected,
              const char* what) const
  {
    REQUIRE(rays.size() == expected.size());
    for (int p = 0; p < 2; ++p) {
      const auto ids = Ids(rays, p);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const RayRecord& r = rays[i];
        INFO(what, " ray ", i, " (", PrecisionName(kPrecisions[p]), "): o = (", r.org[0], ", ", r.org[1], ", ",
             r.org[2], ") d = (", r.dir[0], ", ", r.dir[1], ", ", r.dir[2], ")");
        CHECK(ids[i] == expected[i]);
      }
    }
  }
};

// Spheres of radius 0.3 at the integer points of [0, 3]^3, id = 16x + 4y + z.
std::string SphereLattice()
{
  std::string s;
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z) s += Sphere3(x, y, z, 0.3);
  return s;
}

// Slabs: squares x = i + 0.5 (id i, i = 0..7), spanning y, z in [1, 9].
std::string Slabs()
{
  std::string s;
  for (int i = 0; i < 8; ++i) {
    double x = i + 0.5;
    s += Quad({x, 1, 1}, {x, 9, 1}, {x, 9, 9}, {x, 1, 9});
  }
  return s;
}

// First slab met by a ray (slabs as in Slabs()), CR_NO_HIT if none; -1 when
// the answer is too close to an edge of a slab to be a fair test.
long SlabHit(const RayRecord& r)
{
  const double dx = r.dir[0];
  if (dx == 0.0) return CR_NO_HIT;
  long best = CR_NO_HIT;
  double bestT = INFINITY;
  for (int i = 0; i < 8; ++i) {
    const double t = (i + 0.5 - double(r.org[0])) / dx;
    if (std::fabs(t - r.tmin) < 1e-4) return -1;
    if (!(t >= r.tmin && t <= r.tmax) || t >= bestT) continue;
    const double y = r.org[1] + t * double(r.dir[1]), z = r.org[2] + t * double(r.dir[2]);
    const double m = std::min(std::min(y - 1.0, 9.0 - y), std::min(z - 1.0, 9.0 - z));
    if (std::fabs(m) < 1e-3) return -1;
    if (m > 0.0) {
      best = i;
      bestT = t;
    }
  }
  return best;
}

}  // namespace

TEST_CASE("grid: builder invariants (layout, sorted refs, every primitive present, box covers the scene)")
{
  GridCase c(SphereLattice() + Slabs(), 4.0);
  const GridHeader& h = c.H();
  CHECK(h.nCells == h.res[0] * h.res[1] * h.res[2]);
  REQUIRE(c.grid.cellStart.size() == h.nCells + 1u);
  CHECK(c.grid.cellStart[0] == 0u);
  CHECK(c.grid.cellStart[h.nCells] == h.nRefs);
  CHECK(c.grid.refs.size() == h.nRefs);
  std::set<std::uint32_t> seen;
  bool sorted = true;
  for (std::uint32_t i = 0; i < h.nCells; ++i) {
    for (std::uint32_t k = c.grid.cellStart[i]; k < c.grid.cellStart[i + 1]; ++k) {
      seen.insert(c.grid.refs[k]);
      if (k > c.grid.cellStart[i] && !(c.grid.refs[k - 1] < c.grid.refs[k])) sorted = false;
    }
  }
  CHECK(sorted);
  CHECK(seen.size() == c.scene.NumUnified());
  const Bounds wb = c.scene.WorldBounds();
  for (int a = 0; a < 3; ++a) {
    CHECK(h.bmin[a] < wb.lo[a]);
    CHECK(h.bmax[a] > wb.hi[a]);
    CHECK(h.bmax[a] == c.Plane(a, c.Res(a)));
    for (int i = 0; i < c.Res(a); ++i) CHECK(c.Plane(a, i) < c.Plane(a, i + 1));
  }
  // A sphere occupies only cells its surface meets: the lattice sphere at
  // (1, 1, 1) is far smaller than the scene, so it is in few cells.
  std::uint32_t cellsOfSphere = 0;
  const std::uint32_t g = 16 + 4 + 1;
  for (std::uint32_t i = 0; i < h.nCells; ++i)
    for (std::uint32_t k = c.grid.cellStart[i]; k < c.grid.cellStart[i + 1]; ++k) cellsOfSphere += c.grid.refs[k] == g;
  CHECK(cellsOfSphere >= 1u);
  CHECK(cellsOfSphere <= 8u);
}

TEST_CASE("grid: the cost model gives a small object on a large ground more cells per primitive than a cloud")
{
  // A cloud of 512 equal spheres filling its box: the rays end after a few
  // cells whatever the resolution, a coarse grid is enough. SPD tree: a
  // tree on a ground 6 times its size, which only fine cells separate.
  std::string cloud = "v\nfrom 0.5 0.5 4\nat 0.5 0.5 0.5\nup 0 1 0\nangle 40\nhither 0\nresolution 64 64\n"
                      "f 1 1 1 1 0 0 0 1\n";
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 512; ++i) cloud += Sphere3(u(rng), u(rng), u(rng), 0.04);
  AccelInfo info;
  const GridData c = BuildGrid(SceneFromNFF(cloud), AccelParams{}, info);
  MESSAGE("cloud: ", info.params);
  CHECK(info.params.find("(cost model)") != std::string::npos);
  const double cloudCells = double(c.header.nCells) / 512.0;
  const Scene& tree = test::CachedScene(test::SpdPath("tree"));
  const GridData t = BuildGrid(tree, AccelParams{}, info);
  MESSAGE("tree: ", info.params);
  const double treeCells = double(t.header.nCells) / double(tree.NumUnified());
  CHECK(cloudCells <= 8.0);
  CHECK(treeCells >= 4.0 * cloudCells);
  // An explicit density is used as given.
  AccelParams p;
  p.gridDensity = 16.0;
  (void)BuildGrid(tree, p, info);
  CHECK(info.params.find("density=16 ") == 0);
}

TEST_CASE("grid: density parameter (default, explicit, absurd values)")
{
  Scene s = SceneFromNFF(SphereLattice());
  AccelInfo info;
  AccelParams p;
  p.gridDensity = 1.0;
  GridData g1 = BuildGrid(s, p, info);
  CHECK(info.params.find("density=1 ") == 0);
  p.gridDensity = 8.0;
  GridData g8 = BuildGrid(s, p, info);
  CHECK(g8.header.nCells > g1.header.nCells);
  // About lambda * N cells, cubic for a cubic scene.
  CHECK(g8.header.res[0] == g8.header.res[1]);
  CHECK(g8.header.res[1] == g8.header.res[2]);
  CHECK(double(g8.header.nCells) > 0.5 * 8.0 * 64.0);
  CHECK(double(g8.header.nCells) < 2.0 * 8.0 * 64.0);
  CHECK(info.nodes == g8.header.nCells);
  CHECK(info.refs == g8.header.nRefs);
  CHECK(info.bytes == sizeof(GridHeader) + 4u * (g8.header.nCells + 1u) + 4u * g8.header.nRefs);
  p.gridDensity = -1.0;
  CHECK_THROWS_AS(BuildGrid(s, p, info), InputError);
  p.gridDensity = std::nan("");
  CHECK_THROWS_AS(BuildGrid(s, p, info), InputError);
  p.gridDensity = INFINITY;
  CHECK_THROWS_AS(BuildGrid(s, p, info), InputError);
  // Huge but finite: clamped with a warning, never a crash.
  SetWarningsQuiet(true);
  p.gridDensity = 1e12;
  GridData big = BuildGrid(s, p, info);
  SetWarningsQuiet(false);
  CHECK(big.header.nCells <= (1u << 28));
  CHECK(big.header.res[0] <= 4096u);
}

TEST_CASE("grid: flat scene (zero extent on an axis) gets res 1 there and the cells elsewhere")
{
  // 16 triangles in the plane z = 2.
  std::string nff;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) nff += Tri({i, j, 2}, {i + 1, j, 2}, {i, j + 1, 2});
  GridCase c(nff, 4.0);
  CHECK(c.H().res[2] == 1u);
  CHECK(c.H().res[0] == 8u);
  CHECK(c.H().res[1] == 8u);
  // Straight down onto triangle (1, 2) (id 4 * 1 + 2), and along the plane.
  std::vector<RayRecord> rays = {MakeRay({1.25f, 2.25f, 5.0f}, {0.0f, 0.0f, -1.0f}),
                                 MakeRay({1.25f, 2.25f, -5.0f}, {-0.0f, 0.0f, 1.0f}),
                                 MakeRay({3.75f, 3.75f, 5.0f}, {0.0f, -0.0f, -1.0f})};
  c.Expect(rays, {6u, 6u, CR_NO_HIT}, "flat");
}

TEST_CASE("grid: axis-parallel rays with +0 and -0 direction components")
{
  GridCase c(SphereLattice(), 4.0);
  std::vector<RayRecord> rays;
  std::vector<std::uint32_t> expected;
  const float zeros[2] = {0.0f, -0.0f};
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int sgn = 0; sgn < 2; ++sgn)
          for (float zu : zeros)
            for (float zv : zeros) {
              // Through the sphere centres of line (a, b), and 0.2 off them.
              for (float off : {0.0f, 0.2f}) {
                glm::vec3 o, d;
                o[axis] = sgn ? 10.0f : -10.0f;
                o[u] = float(a) + off;
                o[v] = float(b) - off;
                d[axis] = sgn ? -1.0f : 1.0f;
                d[u] = zu;
                d[v] = zv;
                rays.push_back(MakeRay(o, d));
                int p[3];
                p[axis] = sgn ? 3 : 0;
                p[u] = a;
                p[v] = b;
                expected.push_back(std::uint32_t(16 * p[0] + 4 * p[1] + p[2]));
              }
            }
  }
  c.Expect(rays, expected, "axis-parallel");
  // Between the lattice lines the same rays meet nothing.
  std::vector<RayRecord> misses;
  for (float zu : zeros)
    for (float zv : zeros) {
      misses.push_back(MakeRay({-10.0f, 0.5f, 1.5f}, {1.0f, zu, zv}));
      misses.push_back(MakeRay({1.5f, 10.0f, 2.5f}, {zu, -1.0f, zv}));
      misses.push_back(MakeRay({2.5f, 0.5f, -10.0f}, {zu, zv, 1.0f}));
    }
  c.Expect(misses, std::vector<std::uint32_t>(misses.size(), CR_NO_HIT), "axis-parallel miss");
}

TEST_CASE("grid: rays starting inside the grid exactly on cell planes, edges and corners")
{
  GridCase c(Slabs(), 8.0);
  REQUIRE(c.Res(0) >= 4);
  std::vector<RayRecord> rays;
  std::vector<std::uint32_t> expected;
  const glm::vec3 dirs[] = {{1.0f, 0.0f, 0.0f},   {-1.0f, 0.0f, 0.0f},  {1.0f, -0.0f, -0.0f}, {-1.0f, -0.0f, 0.0f},
                            {1.0f, 0.1f, 0.05f},  {-1.0f, 0.1f, -0.2f}, {1.0f, 1.0f, 1.0f},   {-1.0f, -1.0f, -1.0f},
                            {0.25f, -0.125f, 0.0f}, {-3.0f, 0.0f, 1.0f}};
  for (int i = 1; i < c.Res(0); ++i)
    for (int j = 1; j < c.Res(1); ++j)
      for (int k = 1; k < c.Res(2); ++k) {
        // Origins on a cell corner, on an edge (x, y planes) and on a face (x plane).
        const glm::vec3 corner(c.Plane(0, i), c.Plane(1, j), c.Plane(2, k));
        const glm::vec3 origins[] = {corner, {corner.x, corner.y, corner.z + 0.3f}, {corner.x, corner.y + 0.3f, corner.z + 0.2f}};
        for (const glm::vec3& o : origins)
          for (const glm::vec3& d : dirs) {
            RayRecord r = MakeRay(o, d);
            long e = SlabHit(r);
            if (e < 0) continue;
            rays.push_back(r);
            expected.push_back(std::uint32_t(e));
          }
      }
  REQUIRE(rays.size() > 100u);
  c.Expect(rays, expected, "on cell planes");
}

TEST_CASE("grid: rays on the grid box and lying in grid face planes (grazing)")
{
  GridCase c(Slabs(), 8.0);
  const GridHeader& h = c.H();
  std::vector<RayRecord> rays;
  std::vector<std::uint32_t> expected;
  // Along the outer faces y = bmin and z = bmax: no geometry there (padding).
  for (float z0 : {0.0f, -0.0f}) {
    rays.push_back(MakeRay({-5.0f, h.bmin[1], 5.0f}, {1.0f, z0, z0}));
    rays.push_back(MakeRay({20.0f, 5.0f, h.bmax[2]}, {-1.0f, z0, z0}));
    rays.push_back(MakeRay({h.bmin[0], h.bmin[1], h.bmin[2]}, {1.0f, z0, z0}));  // along a grid edge
    rays.push_back(MakeRay({h.bmax[0], 3.0f, h.bmin[2]}, {-1.0f, 1.0f, z0}));    // in the face z = bmin
    expected.insert(expected.end(), 4, CR_NO_HIT);
  }
  // Starting exactly on the grid box, into the grid: the first slab.
  rays.push_back(MakeRay({h.bmin[0], 5.0f, 5.0f}, {1.0f, 0.0f, 0.0f}));
  expected.push_back(0u);
  rays.push_back(MakeRay({h.bmax[0], 5.0f, 5.0f}, {-1.0f, -0.0f, 0.0f}));
  expected.push_back(7u);
  rays.push_back(MakeRay({h.bmin[0], 2.0f, 3.0f}, {1.0f, 0.5f, 0.25f}));
  expected.push_back(0u);
  // Starting outside, the interval beginning exactly on the box face.
  rays.push_back(MakeRay({h.bmin[0] - 1.0f, 4.0f, 4.0f}, {1.0f, 0.0f, 0.0f}, 1.0f));
  expected.push_back(0u);
  // Lying in interior cell planes y = plane j (and z = plane k): hits the slabs.
  for (int j = 1; j < c.Res(1); ++j)
    for (float z0 : {0.0f, -0.0f}) {
      const float y = c.Plane(1, j), z = c.Plane(2, std::min(j, c.Res(2) - 1));
      if (y <= 1.001f || y >= 8.999f || z <= 1.001f || z >= 8.999f) continue;
      rays.push_back(MakeRay({-5.0f, y, z}, {1.0f, z0, z0}));
      expected.push_back(0u);
      rays.push_back(MakeRay({20.0f, y, z}, {-1.0f, z0, -z0}));
      expected.push_back(7u);
      rays.push_back(MakeRay({-5.0f, y, 5.0f}, {1.0f, z0, 0.1f}));
      expected.push_back(0u);
    }
  c.Expect(rays, expected, "grazing");
}

TEST_CASE("grid: rays through cell corners")
{
  GridCase c(Slabs(), 8.0);
  std::vector<RayRecord> rays;
  std::vector<std::uint32_t> expected;
  for (int i = 1; i < c.Res(0); ++i)
    for (int j = 1; j < c.Res(1); ++j)
      for (int k = 1; k < c.Res(2); ++k) {
        const glm::vec3 corner(c.Plane(0, i), c.Plane(1, j), c.Plane(2, k));
        if (!(corner.x > 0.0f && corner.y > 0.0f && corner.z > 0.0f)) continue;
        for (float fx : {0.9375f, 1.0625f})
          for (float fy : {0.9375f, 1.0625f})
            for (float fz : {0.9375f, 1.0625f}) {
              // o within a factor 2 of the corner, so d = corner - o is exact
              // (Sterbenz) and the exact ray passes through the corner at t = 1.
              const glm::vec3 o(corner.x * fx, corner.y * fy, corner.z * fz);
              const glm::vec3 d = corner - o;
              REQUIRE(o + d == corner);
              RayRecord r = MakeRay(o, d);
              long e = SlabHit(r);
              if (e < 0) continue;
              rays.push_back(r);
              expected.push_back(std::uint32_t(e));
            }
      }
  REQUIRE(rays.size() > 100u);
  c.Expect(rays, expected, "through corners");
}

TEST_CASE("grid: a primitive spanning cells, hit beyond the first cell's exit")
{
  // A long triangle in the plane y = 0.5 + 0.001 (x - 5) (the scene is flat
  // in y, so one cell spans y): it passes through the cell the ray starts in
  // (x = 1.5) but the ray meets it at x = 5, t = 3.5. A small sphere (id 1)
  // lies farther (t = 6.5) or nearer (t = 2).
  const std::string tri = Tri({-1.0, 0.494, -5.0}, {11.0, 0.506, -5.0}, {5.0, 0.5, 10.0});
  const RayRecord ray = MakeRay({1.5f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f});
  for (double density : {4.0, 16.0, 64.0}) {
    INFO("density ", density);
    GridCase far(tri + Sphere3(8.0, 0.5, 0.5, 0.004), density);
    GridCase near(tri + Sphere3(3.5, 0.5, 0.5, 0.004), density);
    // The set-up: the triangle (unified index 1, after the sphere) is a
    // reference of the ray's first cell, and x = 5 lies beyond that cell.
    const GridHeader& h = far.H();
    int cell[3];
    for (int a = 0; a < 3; ++a) {
      cell[a] = 0;
      while (cell[a] + 1 < far.Res(a) && far.Plane(a, cell[a] + 1) <= ray.org[a]) ++cell[a];
    }
    const std::uint32_t idx =
        std::uint32_t(cell[0]) + h.res[0] * (std::uint32_t(cell[1]) + h.res[1] * std::uint32_t(cell[2]));
    bool triInFirst = false;
    for (std::uint32_t k = far.grid.cellStart[idx]; k < far.grid.cellStart[idx + 1]; ++k)
      triInFirst = triInFirst || far.grid.refs[k] == 1u;
    REQUIRE(triInFirst);
    REQUIRE(far.Plane(0, cell[0] + 1) < 5.0f);

    far.Expect({ray}, {0u}, "spanning, farther sphere");
    near.Expect({ray}, {1u}, "spanning, nearer sphere");
    // Occlusion: blocked iff something lies in [tmin, tmax].
    RayRecord shortRay = ray, longRay = ray;
    shortRay.tmax = 3.0f;
    longRay.tmax = 4.0f;
    for (int p = 0; p < 2; ++p) {
      const auto ids = far.Ids({shortRay, longRay}, p, true);
      CHECK(ids[0] == CR_NO_HIT);
      CHECK(ids[1] == 0u);
      CHECK(near.Ids({shortRay}, p, true)[0] == 1u);
    }
  }
}

TEST_CASE("grid: rays from inside a closed triangulated box toward its vertices and edges all hit")
{
  // A cube rotated about two axes, 12 triangles (ids 0..11), each face split
  // along a diagonal, so triangles cross many cells obliquely.
  const double ca = std::cos(0.5), sa = std::sin(0.5), cb = std::cos(0.3), sb = std::sin(0.3);
  auto rot = [&](glm::dvec3 p) {
    glm::dvec3 q(ca * p.x - sa * p.y, sa * p.x + ca * p.y, p.z);
    return glm::dvec3(q.x, cb * q.y - sb * q.z, sb * q.y + cb * q.z) + glm::dvec3(3.0, 2.0, 1.0);
  };
  glm::dvec3 v[8];
  for (int i = 0; i < 8; ++i) v[i] = rot(glm::dvec3(i & 1 ? 2.0 : -2.0, i & 2 ? 2.0 : -2.0, i & 4 ? 2.0 : -2.0));
  // Faces as vertex quads, split into (a, b, c) and (a, c, d).
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  std::string nff;
  std::vector<std::array<int, 3>> tris;
  for (const auto& f : faces) {
    tris.push_back({f[0], f[1], f[2]});
    tris.push_back({f[0], f[2], f[3]});
  }
  // Parse vertices through float so that the scene and this test agree.
  glm::vec3 vf[8];
  for (int i = 0; i < 8; ++i) vf[i] = glm::vec3(v[i]);
  for (const auto& t : tris)
    nff += fmt::format("p 3\n{} {} {}\n{} {} {}\n{} {} {}\n", vf[t[0]].x, vf[t[0]].y, vf[t[0]].z, vf[t[1]].x,
                       vf[t[1]].y, vf[t[1]].z, vf[t[2]].x, vf[t[2]].y, vf[t[2]].z);
  // Targets: vertices, and points on every triangle edge (box edges and face
  // diagonals), each with the triangles that contain it.
  struct Target {
    glm::vec3 p;
    std::set<std::uint32_t> ids;
  };
  std::vector<Target> targets;
  for (int i = 0; i < 8; ++i) {
    Target t{vf[i], {}};
    for (std::uint32_t k = 0; k < 12; ++k)
      if (tris[k][0] == i || tris[k][1] == i || tris[k][2] == i) t.ids.insert(k);
    targets.push_back(t);
  }
  for (std::uint32_t k = 0; k < 12; ++k)
    for (int e = 0; e < 3; ++e) {
      const int a = tris[k][e], b = tris[k][(e + 1) % 3];
      for (float s : {0.5f, 0.25f, 0.8125f}) {
        Target t{vf[a] + s * (vf[b] - vf[a]), {}};
        for (std::uint32_t m = 0; m < 12; ++m) {
          const auto& q = tris[m];
          const bool hasA = q[0] == a || q[1] == a || q[2] == a, hasB = q[0] == b || q[1] == b || q[2] == b;
          if (hasA && hasB) t.ids.insert(m);
        }
        targets.push_back(t);
      }
    }
  for (double density : {1.0, 4.0, 32.0}) {
    INFO("density ", density);
    GridCase c(nff, density);
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> u(-1.9, 1.9);
    std::vector<RayRecord> rays;
    std::vector<const Target*> want;
    for (int n = 0; n < 64; ++n) {
      const glm::vec3 o(rot(glm::dvec3(u(rng), u(rng), u(rng))));
      for (const Target& t : targets) {
        rays.push_back(MakeRay(o, t.p - o));
        want.push_back(&t);
      }
    }
    // Origins on cell planes and corners inside the box as well.
    for (int i = 1; i < c.Res(0); ++i)
      for (int j = 1; j < c.Res(1); ++j)
        for (int k = 1; k < c.Res(2); ++k) {
          const glm::dvec3 o(c.Plane(0, i), c.Plane(1, j), c.Plane(2, k));
          // Keep it only when well inside: beyond 0.05 from every face plane,
          // on the centre's side.
          bool inside = true;
          for (const auto& f : faces) {
            const glm::dvec3 n = glm::cross(v[f[1]] - v[f[0]], v[f[3]] - v[f[0]]) / 16.0;
            const double so = glm::dot(o - v[f[0]], n), sc = glm::dot(glm::dvec3(3.0, 2.0, 1.0) - v[f[0]], n);
            if (!(so * sc > 0.0 && std::fabs(so) > 0.05)) inside = false;
          }
          if (!inside) continue;
          for (const Target& t : targets) {
            rays.push_back(MakeRay(glm::vec3(o), t.p - glm::vec3(o)));
            want.push_back(&t);
          }
        }
    for (int p = 0; p < 2; ++p) {
      const auto ids = c.Ids(rays, p);
      const auto occ = c.Ids(rays, p, true);
      std::size_t bad = 0, badOcc = 0;
      std::string first;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        if (!want[i]->ids.count(ids[i]) && bad++ < 4)
          first += fmt::format(" ray {} o=({}, {}, {}) hit {};", i, rays[i].org[0], rays[i].org[1], rays[i].org[2],
                               ids[i]);
        if (occ[i] == CR_NO_HIT) ++badOcc;
      }
      INFO(PrecisionName(kPrecisions[p]), ": ", rays.size(), " rays;", first);
      CHECK(bad == 0u);
      CHECK(badOcc == 0u);
    }
  }
}
