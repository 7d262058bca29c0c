// Octree: named hard cases for the builder and the traversal (kernels/octree.h,
// host/accel/octree_builder.cpp). Geometry is placed on the octree's own cell
// planes (computed with the kernel's Octree_Plane), so rays run exactly along
// planes, edges and corners of cells.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "host/accel/accel.h"
#include "host/core/error.h"
#include "host/scene/generate.h"
#include "host/trace/tracer.h"
#include "simd/simd_kernels.h"
#include "tests/test_util.h"

using namespace cr;

namespace cr::octree_test_kernel {
#include "kernels/octree.h"
}  // namespace cr::octree_test_kernel

namespace {

constexpr float kInf = INFINITY;
const Precision kPrecisions[] = {Precision::Robust, Precision::Fp64};

Scene SceneFromNFF(const std::string& text)
{
  Scene s;
  ParseNFF(text, "test.nff", s);
  return s;
}

std::string SphereLine(float x, float y, float z, float r) { return fmt::format("s {} {} {} {}\n", x, y, z, r); }

// 8 small spheres (ids 0..7) at the corners of [0, 8]^3: they fix the world
// bounds, hence the root cube, whatever else lies inside.
std::string Frame()
{
  std::string s;
  for (int k = 0; k < 8; ++k) s += SphereLine(8.0f * (k & 1), 8.0f * ((k >> 1) & 1), 8.0f * ((k >> 2) & 1), 0.1f);
  return s;
}

RayRecord RayAt(float ox, float oy, float oz, float dx, float dy, float dz, float tmin = 0.0f, float tmax = kInf)
{
  return RayRecord{{ox, oy, oz}, tmin, {dx, dy, dz}, tmax};
}

AccelParams Params(int leaf, int depth)
{
  AccelParams p;
  p.octreeLeaf = leaf;
  p.octreeDepth = depth;
  return p;
}

std::vector<HitRecord> Trace(const Scene& scene, const AccelParams& params, Precision precision,
                             const std::vector<RayRecord>& rays, bool occlusion, TraceStatsSum* stats = nullptr)
{
  TraceConfig cfg;
  cfg.backend = Backend::Scalar;
  cfg.accel = AccelKind::Octree;
  cfg.precision = precision;
  cfg.params = params;
  cfg.stats = stats != nullptr;
  auto tracer = CreateTracer(scene, cfg);
  std::vector<HitRecord> hits;
  tracer->Trace(rays, hits, occlusion, stats);
  REQUIRE(hits.size() == rays.size());
  return hits;
}

float Plane(const OctreeHeader& h, int axis, unsigned level, unsigned i)
{
  return octree_test_kernel::Octree_Plane(&h, axis, level, i);
}

OctreeHeader HeaderOf(const Scene& scene, const AccelParams& params)
{
  AccelInfo info;
  return BuildOctree(scene, params, info).header;
}

// A ray and the primitive id it must report (CR_NO_HIT: a miss).
struct Case {
  std::string name;
  RayRecord ray;
  std::uint32_t prim;
};

void RunCases(const Scene& scene, const AccelParams& params, const std::vector<Case>& cases)
{
  std::vector<RayRecord> rays;
  for (const Case& c : cases) rays.push_back(c.ray);
  for (Precision prec : kPrecisions)
    for (bool occlusion : {false, true}) {
      const auto hits = Trace(scene, params, prec, rays, occlusion);
      for (std::size_t i = 0; i < cases.size(); ++i) {
        INFO(cases[i].name, " (", PrecisionName(prec), occlusion ? ", occlusion)" : ", closest)");
        if (occlusion)
          CHECK((hits[i].prim == CR_NO_HIT) == (cases[i].prim == CR_NO_HIT));
        else
          CHECK(hits[i].prim == cases[i].prim);
      }
    }
}

}  // namespace

TEST_CASE("octree: rays along cell planes, edges and corners, with +0 and -0 directions")
{
  const AccelParams params = Params(1, 6);
  const OctreeHeader h = HeaderOf(SceneFromNFF(Frame()), params);
  // Cell planes: level 1 (the root's mid planes), 2 and 3.
  const float X1 = Plane(h, 0, 1, 1), Y1 = Plane(h, 1, 1, 1), Z1 = Plane(h, 2, 1, 1);
  const float X2a = Plane(h, 0, 2, 1), Y2a = Plane(h, 1, 2, 1), Z2a = Plane(h, 2, 2, 1);
  const float X2b = Plane(h, 0, 2, 3), Z2b = Plane(h, 2, 2, 3);
  std::string text = Frame();
  text += SphereLine(X1, Y1, Z1, 0.5f);     // 8: at the root's centre, where all eight octants meet
  text += SphereLine(X2b, Y1, Z1, 0.5f);    // 9: further along +x on the same cell edge line
  text += SphereLine(X1, Y1, Z2b, 0.5f);    // 10: further along +z
  text += SphereLine(X2a, Y2a, Z2a, 0.5f);  // 11: at a level-2 corner
  text += SphereLine(Plane(h, 0, 3, 5), Plane(h, 1, 3, 3), Plane(h, 2, 3, 6), 0.3f);  // 12: at a level-3 corner
  const Scene scene = SceneFromNFF(text);
  AccelInfo info;
  const OctreeData oct = BuildOctree(scene, params, info);
  REQUIRE(oct.header.rootSize == h.rootSize);  // same bounds, same root
  REQUIRE(oct.header.rootMin[0] == h.rootMin[0]);
  CHECK(oct.header.maxDepth >= 3);

  const float z = 0.0f, nz = -0.0f;
  std::vector<Case> cases;
  // Along the cell edge line y = Y1, z = Z1 (two cell planes), every sign of zero.
  for (float sy : {z, nz})
    for (float sz : {z, nz}) {
      const std::string zs = fmt::format(" dir (.., {}0, {}0)", std::signbit(sy) ? "-" : "+", std::signbit(sz) ? "-" : "+");
      cases.push_back({"edge line +x from outside" + zs, RayAt(-1.0f, Y1, Z1, 1.0f, sy, sz), 8});
      cases.push_back({"edge line -x from outside" + zs, RayAt(9.0f, Y1, Z1, -1.0f, sy, sz), 9});
      cases.push_back({"edge line +x between spheres" + zs, RayAt(X1 + 1.0f, Y1, Z1, 1.0f, sy, sz), 9});
      cases.push_back({"edge line -x between spheres" + zs, RayAt(X1 + 1.0f, Y1, Z1, -1.0f, sy, sz), 8});
      cases.push_back({"from the corner point inside sphere 8" + zs, RayAt(X1, Y1, Z1, 1.0f, sy, sz), 8});
      cases.push_back({"from a level-2 plane on the edge line" + zs, RayAt(X2a, Y1, Z1, 1.0f, sy, sz), 8});
      cases.push_back({"from a level-2 plane, leaving" + zs, RayAt(X2a, Y1, Z1, -1.0f, sy, sz), CR_NO_HIT});
      // In the face plane x = X1 (direction x = +-0), along y and along z.
      cases.push_back({"face plane x=X1 along +y" + zs, RayAt(X1, -1.0f, Z1 + 0.2f, sy, 1.0f, sz), 8});
      cases.push_back({"face plane x=X1 along -z" + zs, RayAt(X1, Y1 + 0.3f, 9.0f, sy, sz, -1.0f), 10});
      cases.push_back({"face plane z=Z1 along +x" + zs, RayAt(-1.0f, Y1 + 0.3f, Z1, 1.0f, sy, sz), 8});
      // Grazing the face plane from either side, by one ulp.
      cases.push_back({"one ulp below the face plane" + zs, RayAt(std::nextafter(X1, -kInf), -1.0f, Z1, sy, 1.0f, sz), 8});
      cases.push_back({"one ulp above the face plane" + zs, RayAt(std::nextafter(X1, kInf), -1.0f, Z1, sy, 1.0f, sz), 8});
      // Along the z axis through the level-3 corner of sphere 12.
      cases.push_back({"edge line of level 3 along -z" + zs,
                       RayAt(Plane(h, 0, 3, 5), Plane(h, 1, 3, 3), 9.0f, sy, sz, -1.0f), 12});
    }
  // Through the root's centre along the eight diagonals, from 1.5 away.
  for (int s = 0; s < 8; ++s) {
    const float dx = (s & 1) ? 1.0f : -1.0f, dy = (s & 2) ? 1.0f : -1.0f, dz = (s & 4) ? 1.0f : -1.0f;
    cases.push_back({fmt::format("diagonal through the root centre, octant {}", s),
                     RayAt(X1 + 1.5f * dx, Y1 + 1.5f * dy, Z1 + 1.5f * dz, -dx, -dy, -dz), 8});
  }
  // The diagonal through the level-2 corner: sphere 11 first, then sphere 8.
  cases.push_back({"diagonal through a level-2 corner", RayAt(X2a - 1.0f, Y2a - 1.0f, Z2a - 1.0f, 1.0f, 1.0f, 1.0f), 11});
  cases.push_back({"diagonal from a level-2 corner, tmin past sphere 11",
                   RayAt(X2a, Y2a, Z2a, X1 - X2a, Y1 - Y2a, Z1 - Z2a, 0.5f), 8});
  // Origins on the root box.
  const float rx = Plane(h, 0, 0, 0), ry = Plane(h, 1, 0, 0), rz = Plane(h, 2, 0, 0);
  cases.push_back({"from the root's -x face, inward", RayAt(rx, Y1, Z1, 1.0f, z, z), 8});
  cases.push_back({"from the root's -x face, outward", RayAt(rx, Y1, Z1, -1.0f, z, z), CR_NO_HIT});
  cases.push_back({"from the root's +x face, inward", RayAt(Plane(h, 0, 0, 1), Y1, Z1, -1.0f, nz, nz), 9});
  cases.push_back({"from the root's corner to frame sphere 0", RayAt(rx, ry, rz, 1.0f, 1.0f, 1.0f), 0});
  cases.push_back({"along the root's -x face plane, 0.108 from sphere 0 (radius 0.1)", RayAt(rx, -1.0f, 0.0f, z, 1.0f, z), CR_NO_HIT});
  cases.push_back({"tmax before the first sphere", RayAt(-1.0f, Y1, Z1, 1.0f, z, z, 0.0f, X1 - 0.5f + 0.9f), CR_NO_HIT});
  RunCases(scene, params, cases);
}

TEST_CASE("octree: a primitive hit beyond the first leaf's exit, nearer ones in between")
{
  // Ray along +x at y = z = 4.3. Triangle 8 lies along the ray from x = 0.5
  // to 7.5 (in every leaf the ray crosses) and is hit at x = 6; sphere 9
  // is hit at x = 7 and sphere 10 at x = 3.3.
  const std::string tri = "p 3\n0.5 3.8 4.575\n7.5 3.8 4.225\n6.5 5 4.275\n";
  const std::string far = SphereLine(7.2f, 4.3f, 4.3f, 0.2f);
  const std::string near = SphereLine(3.5f, 4.3f, 4.3f, 0.2f);
  const Scene withoutNear = SceneFromNFF(Frame() + tri + far);
  const Scene withNear = SceneFromNFF(Frame() + tri + far + near);
  const std::vector<RayRecord> rays = {RayAt(0.5f, 4.3f, 4.3f, 1.0f, 0.0f, 0.0f)};
  const AccelParams params = Params(1, 6);
  for (Precision prec : kPrecisions) {
    INFO(PrecisionName(prec));
    TraceStatsSum st;
    auto hits = Trace(withoutNear, params, prec, rays, false, &st);
    CHECK(hits[0].prim == 8);
    CHECK(hits[0].t == doctest::Approx(5.5).epsilon(1e-5));
    // The triangle was met (beyond the exit) in several leaves before its own.
    CHECK(st.nLeaves >= 3);
    CHECK(st.nIT >= 3);
    hits = Trace(withNear, params, prec, rays, false);
    CHECK(hits[0].prim == 10);
    CHECK(hits[0].t == doctest::Approx(2.8).epsilon(1e-5));
  }
}

TEST_CASE("octree: rays from inside a closed triangulated box at its vertices and edges all hit")
{
  // The cube [1, 7]^3, each face a 4x4 grid of quads split into triangles.
  const int n = 4;
  const float lo = 1.0f, step = 1.5f;
  std::string text;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {1.0f, 7.0f})
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          float q[4][3];
          const int ui[4] = {i, i + 1, i + 1, i}, vj[4] = {j, j, j + 1, j + 1};
          for (int k = 0; k < 4; ++k) {
            q[k][axis] = side;
            q[k][(axis + 1) % 3] = lo + step * float(ui[k]);
            q[k][(axis + 2) % 3] = lo + step * float(vj[k]);
          }
          auto vtx = [&](int k) { return fmt::format("{} {} {}\n", q[k][0], q[k][1], q[k][2]); };
          text += "p 3\n" + vtx(0) + vtx(1) + vtx(2);
          text += "p 3\n" + vtx(0) + vtx(2) + vtx(3);
        }
  const Scene scene = SceneFromNFF(text);
  const AccelParams params = Params(2, 6);
  const OctreeHeader h = HeaderOf(scene, params);
  // Targets: every grid vertex, edge midpoint and diagonal midpoint.
  std::vector<std::array<float, 3>> targets;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {1.0f, 7.0f})
      for (int i = 0; i <= 2 * n; ++i)
        for (int j = 0; j <= 2 * n; ++j) {
          std::array<float, 3> p;
          p[axis] = side;
          p[(axis + 1) % 3] = lo + 0.5f * step * float(i);
          p[(axis + 2) % 3] = lo + 0.5f * step * float(j);
          targets.push_back(p);
        }
  const std::vector<std::array<float, 3>> origins = {{4.0f, 4.0f, 4.0f},
                                                     {2.5f, 3.1f, 5.9f},
                                                     {1.75f, 1.75f, 6.25f},
                                                     {Plane(h, 0, 1, 1), Plane(h, 1, 1, 1), Plane(h, 2, 1, 1)},
                                                     {Plane(h, 0, 2, 1), Plane(h, 1, 1, 1), 5.3f},
                                                     {Plane(h, 0, 3, 2), Plane(h, 1, 3, 5), Plane(h, 2, 3, 3)}};
  std::vector<RayRecord> rays;
  for (const auto& o : origins)
    for (const auto& p : targets) rays.push_back(RayAt(o[0], o[1], o[2], p[0] - o[0], p[1] - o[1], p[2] - o[2]));
  for (Precision prec : kPrecisions)
    for (bool occlusion : {false, true}) {
      INFO(PrecisionName(prec), occlusion ? " occlusion" : " closest");
      const auto hits = Trace(scene, params, prec, rays, occlusion);
      std::size_t nMissed = 0, nFar = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        nMissed += hits[i].prim == CR_NO_HIT;
        if (!occlusion && hits[i].prim != CR_NO_HIT) nFar += std::fabs(hits[i].t - 1.0f) > 1e-5f;
      }
      CHECK(rays.size() == origins.size() * 6 * 81);
      CHECK(nMissed == 0);
      CHECK(nFar == 0);
    }
}

TEST_CASE("octree: 1000 coincident spheres stop at the depth limit and keep the lowest id on the exact tie")
{
  std::string text = Frame();
  for (int i = 0; i < 1000; ++i) text += SphereLine(3.3f, 4.6f, 5.1f, 0.05f);  // ids 8..1007
  const Scene scene = SceneFromNFF(text);
  const std::vector<RayRecord> rays = {RayAt(3.3f, 4.6f, -1.0f, 0.0f, 0.0f, 1.0f),  // through the centre
                                       RayAt(3.3f, 4.6f, 5.1f, 0.3f, -0.2f, 1.0f),  // from the centre
                                       RayAt(3.32f, 4.59f, 9.0f, 0.0f, -0.0f, -1.0f)};
  for (int depth : {4, 6}) {
    AccelInfo info;
    const OctreeData oct = BuildOctree(scene, Params(8, depth), info);
    INFO("depth ", depth, ": ", info.params);
    // The cluster (0.1 wide) is far smaller than a cell at this depth: the
    // subdivision runs to the limit and stops there, with a few copies.
    CHECK(oct.header.maxDepth == unsigned(depth));
    CHECK(oct.refs.size() <= 8 * 1000 + 8);
  }
  // At the deepest level supported the cells get smaller than the spheres;
  // splitting stops where it no longer separates anything.
  AccelInfo info;
  const OctreeData deep = BuildOctree(scene, Params(1, CR_OCTREE_MAX_DEPTH), info);
  INFO(info.params);
  CHECK(deep.header.maxDepth <= unsigned(CR_OCTREE_MAX_DEPTH));
  CHECK(deep.refs.size() <= 64 * 1000);
  for (int depth : {6, CR_OCTREE_MAX_DEPTH})
    for (Precision prec : kPrecisions) {
      INFO("depth ", depth, " ", PrecisionName(prec));
      auto hits = Trace(scene, Params(1, depth), prec, rays, false);
      for (const auto& hit : hits) CHECK(hit.prim == 8);
      hits = Trace(scene, Params(1, depth), prec, rays, true);
      for (const auto& hit : hits) CHECK(hit.prim != CR_NO_HIT);
    }
}

TEST_CASE("octree: beyond depth 10 a crowded node splits on where the surface area heuristic finds it pays")
{
  // The teapot in a stadium: at depth 10 a cell is 15 units wide and holds
  // the whole sphereflake; the default goes on down where splitting pays.
  const Scene scene = GenerateStadium(3);
  AccelInfo info;
  const OctreeData fixed = BuildOctree(scene, Params(12, 10), info);
  CHECK(fixed.header.maxDepth == 10u);
  const OctreeData deep = BuildOctree(scene, AccelParams{}, info);
  INFO(info.params);
  CHECK(deep.header.maxDepth > 12u);
  CHECK(info.params.find("depth=10+sah..20") != std::string::npos);
  const auto rays = test::MakeRays(scene, RayKind::Diffuse, 48);
  TraceStatsSum a, b;
  (void)Trace(scene, Params(12, 10), Precision::Robust, rays, false, &a);
  (void)Trace(scene, AccelParams{}, Precision::Robust, rays, false, &b);
  MESSAGE("tests per diffuse ray: depth 10 ", double(a.nIT) / rays.size(), ", default ", double(b.nIT) / rays.size());
  CHECK(b.nIT * 4 < a.nIT);
  TraceConfig cfg;
  cfg.accel = AccelKind::Octree;
  for (Backend backend : {Backend::Scalar, Backend::Simd})
    for (bool occlusion : {false, true}) {
      cfg.backend = backend;
      CHECK(test::CheckTracer(scene, cfg, rays, occlusion).wrong == 0);
    }
  // The heuristic everywhere (--octree-build sah) answers alike.
  cfg.backend = Backend::Scalar;
  cfg.params.octreeBuild = "sah";
  CHECK(test::CheckTracer(scene, cfg, rays, false).wrong == 0);
}

TEST_CASE("octree: parameters are validated")
{
  const Scene scene = SceneFromNFF(Frame());
  AccelInfo info;
  AccelParams bad;
  bad.octreeBuild = "deep";
  CHECK_THROWS_AS(BuildOctree(scene, bad, info), InputError);
  CHECK_THROWS_AS(BuildOctree(scene, Params(-1, 0), info), InputError);
  CHECK_THROWS_AS(BuildOctree(scene, Params(0, -1), info), InputError);
  CHECK_THROWS_AS(BuildOctree(scene, Params(0, CR_OCTREE_MAX_DEPTH + 1), info), InputError);
  CHECK_NOTHROW(BuildOctree(scene, Params(1, 1), info));
  CHECK_NOTHROW(BuildOctree(scene, Params(1, CR_OCTREE_MAX_DEPTH), info));
}

TEST_CASE("octree: layout invariants on the SPD scenes")
{
  for (const std::string& name : test::SpdScenes()) {
    INFO(name);
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    AccelInfo info;
    const OctreeData oct = BuildOctree(scene, AccelParams{}, info);
    const OctreeHeader& h = oct.header;
    REQUIRE(h.nNodes == oct.nodes.size());
    REQUIRE(h.nRefs == oct.refs.size());
    CHECK(h.maxDepth <= unsigned(CR_OCTREE_MAX_DEPTH));
    CHECK(info.nodes == oct.nodes.size());
    CHECK(info.refs == oct.refs.size());
    // The root cube holds every primitive.
    const Bounds wb = scene.WorldBounds();
    for (int a = 0; a < 3; ++a) {
      CHECK(Plane(h, a, 0, 0) < wb.lo[a]);
      CHECK(Plane(h, a, 0, 1) > wb.hi[a]);
    }
    // Every node is reached once from the root; children contiguous, in
    // octant order; leaves sorted; depths consistent.
    std::vector<int> seen(oct.nodes.size(), 0);
    std::vector<std::uint32_t> todo = {0};
    seen[0] = 1;
    std::uint64_t nLeaves = 0, nEmpty = 0, nRefs = 0;
    bool ok = true;
    while (!todo.empty()) {
      const std::uint32_t i = todo.back();
      todo.pop_back();
      const OctreeNode& nd = oct.nodes[i];
      if (nd.childMask == 0) {
        ++nLeaves;
        nRefs += nd.count;
        ok = ok && nd.first + nd.count <= oct.refs.size();
        for (std::uint32_t k = nd.first; ok && k < nd.first + nd.count; ++k) {
          ok = ok && oct.refs[k] < scene.NumUnified();
          if (k > nd.first) ok = ok && oct.refs[k - 1] < oct.refs[k];
        }
        continue;
      }
      ok = ok && nd.depth < h.maxDepth && nd.childMask < 256;
      const std::uint32_t nKids = std::popcount(nd.childMask);
      nEmpty += 8 - nKids;
      ok = ok && nd.first + nKids <= oct.nodes.size();
      for (std::uint32_t k = 0; ok && k < nKids; ++k) {
        ok = ok && !seen[nd.first + k] && oct.nodes[nd.first + k].depth == nd.depth + 1;
        seen[nd.first + k] = 1;
        todo.push_back(nd.first + k);
      }
    }
    CHECK(ok);
    CHECK(std::count(seen.begin(), seen.end(), 1) == std::ptrdiff_t(oct.nodes.size()));
    CHECK(nRefs == oct.refs.size());
    CHECK(info.leaves == nLeaves + nEmpty);
    CHECK(info.emptyLeaves == nEmpty);
  }
}

TEST_CASE("octree: an empty scene is one empty root leaf that every ray misses")
{
  const Scene scene;
  AccelInfo info;
  const OctreeData oct = BuildOctree(scene, AccelParams{}, info);
  REQUIRE(oct.nodes.size() == 1);
  CHECK(oct.nodes[0].childMask == 0);
  CHECK(oct.nodes[0].count == 0);
  CHECK(info.emptyLeaves == 1);
  const auto hits = Trace(scene, AccelParams{}, Precision::Robust, {RayAt(0.5f, 0.5f, -1.0f, 0.0f, 0.0f, 1.0f)}, false);
  CHECK(hits[0].prim == CR_NO_HIT);
}

TEST_CASE("octree: random rays snapped to cell planes, with +-0 direction components, agree with the reference")
{
  // Origins anywhere in the root cube with some coordinates moved exactly
  // onto a cell plane of a random level; some direction components +0 or -0.
  for (const std::string& name : test::Scenes({"balls", "teapot", "rings", "tetra"})) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    const OctreeHeader h = HeaderOf(scene, AccelParams{});
    std::vector<RayRecord> rays;
    const std::uint64_t n = 6000;
    for (std::uint64_t i = 0; i < n; ++i) {
      auto rnd = [&](std::uint64_t k) { return ToUnit(HashRandom(11, i, k)); };
      const unsigned level = 1 + unsigned(rnd(0) * std::max(1u, h.maxDepth));
      const float cell = h.rootSize * std::ldexp(1.0f, -int(level));
      RayRecord r{};
      bool anyDir = false;
      for (int a = 0; a < 3; ++a) {
        float x = h.rootMin[a] + float(rnd(1 + a)) * h.rootSize;
        if (rnd(4 + a) < 0.6) x = Plane(h, a, level, unsigned(std::lround((x - h.rootMin[a]) / cell)));
        r.org[a] = x;
        float d = float(2.0 * rnd(7 + a) - 1.0);
        if (rnd(10 + a) < 0.35) d = rnd(13 + a) < 0.5 ? 0.0f : -0.0f;
        r.dir[a] = d;
        anyDir = anyDir || d != 0.0f;
      }
      if (!anyDir) r.dir[int(rnd(16) * 3) % 3] = 1.0f;
      r.tmin = 0.0f;
      r.tmax = kInf;
      rays.push_back(r);
    }
    for (Precision prec : kPrecisions)
      for (bool occlusion : {false, true}) {
        TraceConfig cfg;
        cfg.backend = Backend::Scalar;
        cfg.accel = AccelKind::Octree;
        cfg.precision = prec;
        const auto r = test::CheckTracer(scene, cfg, rays, occlusion);
        INFO(name, " ", PrecisionName(prec), occlusion ? " occlusion: " : " closest: ", r.wrong, " wrong of ", r.rays,
             r.firstWrong.empty() ? std::string() : " (first " + std::to_string(r.firstWrong[0]) + ")");
        CHECK(r.wrong == 0);
      }
  }
}

namespace {
// Every walk of the octree: the CPU ones, and OpenCL (per ray and packet)
// where a device is present.
struct OctreePath {
  const char* name;
  Backend backend;
  const char* variant;
  bool statsAsScalar;  // per-ray counts equal the scalar walk's (the OpenCL packet walk counts its own way)
};
std::vector<OctreePath> OctreePaths()
{
  std::vector<OctreePath> paths;
  for (const test::TracePath& p : test::TracePaths())
    paths.push_back({p.name, p.backend, p.variant, !(p.backend == Backend::OpenCL && std::string(p.variant) == "packet")});
  return paths;
}
}  // namespace

TEST_CASE("octree: the mailbox (--octree-mailbox on) gives the classic walk's answers with fewer tests, per ray as on scalar")
{
  // The teapot in a stadium: the ground and stands lie in many leaves, so
  // a ray can meet a primitive again. Every CPU path, and OpenCL (per ray
  // and packet) where a device is present.
  const Scene scene = GenerateStadium(3);
  AccelInfo info;
  AccelParams on;
  on.octreeMailbox = "on";
  const OctreeData tree = BuildOctree(scene, on, info);
  CHECK(tree.header.flags == CR_OCTREE_MAILBOX_ON);
  CHECK(info.params.find("mailbox=on") != std::string::npos);
  CHECK(BuildOctree(scene, AccelParams{}, info).header.flags == 0u);
  AccelParams bad;
  bad.octreeMailbox = "yes";
  CHECK_THROWS_AS(BuildOctree(scene, bad, info), InputError);

  const auto clCache = test::OpenCLTestCacheDir();
  const std::vector<OctreePath> paths = OctreePaths();
  for (RayKind kind : {RayKind::Primary, RayKind::Diffuse}) {
    const auto rays = test::MakeRays(scene, kind, 48);
    for (bool occlusion : {false, true}) {
      TraceStatsSum scalarOn;
      for (const OctreePath& p : paths) {
        CAPTURE(p.name);
        CAPTURE(occlusion);
        std::vector<HitRecord> hits[2];
        TraceStatsSum st[2];
        for (int mb = 0; mb < 2; ++mb) {
          TraceConfig cfg;
          cfg.backend = p.backend;
          cfg.variant = p.variant;
          cfg.accel = AccelKind::Octree;
          cfg.params.octreeMailbox = mb ? "on" : "off";
          cfg.stats = true;
          CreateTracer(scene, cfg)->Trace(rays, Tracer::NoTimes(), hits[mb], occlusion, &st[mb]);
          CHECK(ref::CheckHits(test::CachedReference(scene), rays, hits[mb], occlusion, Tracer::NoTimes()).wrong == 0);
        }
        // Closest hits: the same answers bit for bit. Any hit: hit or miss
        // the same (the occluder reported may differ on the packet walk).
        CHECK(test::CountDiffering(hits[0], hits[1], occlusion) == 0);
        CHECK(st[0].nTS == st[1].nTS);
        MESSAGE(std::string(p.name), (occlusion ? " any hit" : " closest"), ": tests per ray, mailbox off ",
                double(st[0].nIT) / double(rays.size()), ", on ", double(st[1].nIT) / double(rays.size()));
        CHECK(st[1].nIT < st[0].nIT);
        if (p.backend == Backend::Scalar) scalarOn = st[1];
        if (p.statsAsScalar) {
          CHECK(st[1].nIT == scalarOn.nIT);
          CHECK(st[1].nLeaves == scalarOn.nLeaves);
        }
      }
    }
  }
}

TEST_CASE("octree: the ray's margins (--octree-margin ray) on the teapot in a stadium: fewer tests, the same answers, 0 wrong on every path")
{
  // The flake in the stadium is smaller than the scene-relative padding lets
  // the classic octree's cells get; with the ray's own margins its cells
  // hold fewer primitives and the walk tests fewer, with the same closest
  // hits. Every CPU path, and OpenCL (per ray and packet) where a
  // device is present, with and without the mailbox.
  const Scene scene = GenerateStadium(3);
  AccelInfo classicInfo, info;
  AccelParams ray;
  ray.octreeMargin = "ray";
  const OctreeData classic = BuildOctree(scene, AccelParams{}, classicInfo);
  const OctreeData tree = BuildOctree(scene, ray, info);
  CHECK(tree.header.flags == (CR_OCTREE_MARGIN_RAY | CR_OCTREE_LEAF_BOXES));
  CHECK(info.params.find("margin=ray leaf_box=on") != std::string::npos);
  // The flake hangs at the end of a chain of nodes (each with one interior
  // child, the others ground): long enough that the SIMD packets search it
  // lazily (simd/octree_packet.h), so the paths below check that form too;
  // the SPD teapot has no such chain down its heaviest path.
  const std::uint32_t chain = OctreeChainLength(tree);
  MESSAGE("chain: ", chain, " levels");
  CHECK(chain >= simd::kOctreeLazyChain);
  CHECK(tree.chain == chain);
  CHECK(info.params.find(fmt::format("chain={}", chain)) != std::string::npos);
  {
    AccelInfo teapotInfo;
    const OctreeData teapot = BuildOctree(test::CachedScene(test::SpdPath("teapot")), ray, teapotInfo);
    CHECK(OctreeChainLength(teapot) < simd::kOctreeLazyChain);
  }
  // Without the scene's padding fewer cells take each primitive.
  MESSAGE("references: scene margins ", classicInfo.refs, ", ray margins ", info.refs);
  CHECK(info.refs < classicInfo.refs);
  CHECK(classic.refs.size() == classicInfo.refs);
  AccelParams bad;
  bad.octreeMargin = "cell";
  CHECK_THROWS_AS(BuildOctree(scene, bad, info), InputError);
  // Leaf boxes: each non-empty leaf's six words before its references hold
  // a box inside its cell that holds every primitive's bounds clipped to the
  // cell; off, the references are as they were, without boxes.
  {
    std::size_t boxes = 0, checked = 0;
    ForEachOctreeNode(tree, [&](std::uint32_t ni, std::uint32_t level, const std::array<std::uint32_t, 3>& c) {
      const OctreeNode& nd = tree.nodes[ni];
      if (nd.childMask != 0u || nd.count == 0u) return;
      REQUIRE(nd.first >= CR_OCTREE_BOX_WORDS);
      float box[6];
      for (std::uint32_t i = 0; i < 6; ++i) box[i] = std::bit_cast<float>(tree.refs[nd.first - CR_OCTREE_BOX_WORDS + i]);
      ++boxes;
      for (int a = 0; a < 3; ++a) {
        const float clo = octree_test_kernel::Octree_Plane(&tree.header, a, level, c[a]);
        const float chi = octree_test_kernel::Octree_Plane(&tree.header, a, level, c[a] + 1u);
        CHECK(box[a] <= box[3 + a]);
        // Inside the cell (grown by at most the builder's rounding).
        CHECK(box[a] >= clo - 1e-3f * (chi - clo));
        CHECK(box[3 + a] <= chi + 1e-3f * (chi - clo));
        for (std::uint32_t i = nd.first; i < nd.first + nd.count; ++i) {
          const Bounds b = scene.UnifiedBounds(tree.refs[i]);
          CHECK(box[a] <= std::max(b.lo[a], clo));
          CHECK(box[3 + a] >= std::min(b.hi[a], chi));
          ++checked;
        }
      }
    });
    MESSAGE("leaf boxes: ", boxes, ", primitive bounds checked against them: ", checked);
    CHECK(boxes > 100u);
    CHECK(tree.refs.size() == info.refs + CR_OCTREE_BOX_WORDS * boxes);
    AccelParams noBox = ray;
    noBox.octreeLeafBox = "off";
    AccelInfo noBoxInfo;
    const OctreeData plain = BuildOctree(scene, noBox, noBoxInfo);
    CHECK(plain.header.flags == CR_OCTREE_MARGIN_RAY);
    CHECK(plain.refs.size() == info.refs);
    CHECK(noBoxInfo.params.find("leaf_box=off") != std::string::npos);
    AccelParams classicBox;
    classicBox.octreeLeafBox = "on";
    CHECK_THROWS_AS(BuildOctree(scene, classicBox, noBoxInfo), InputError);
    noBox.octreeLeafBox = "yes";
    CHECK_THROWS_AS(BuildOctree(scene, noBox, noBoxInfo), InputError);
  }

  const auto clCache = test::OpenCLTestCacheDir();
  const std::vector<OctreePath> paths = OctreePaths();
  for (RayKind kind : {RayKind::Primary, RayKind::Diffuse}) {
    const auto rays = test::MakeRays(scene, kind, 48);
    for (bool occlusion : {false, true}) {
      TraceConfig base;
      base.accel = AccelKind::Octree;
      base.stats = true;
      std::vector<HitRecord> classicHits;
      TraceStatsSum classicSt;
      CreateTracer(scene, base)->Trace(rays, Tracer::NoTimes(), classicHits, occlusion, &classicSt);
      // (mailbox, root, leaf boxes); the last without boxes, to compare
      // the tests per ray with the second.
      struct Combo {
        const char *mailbox, *root, *leafBox;
      };
      const Combo combos[] = {{"off", "centre", "on"}, {"off", "offset", "on"}, {"on", "centre", "on"},
                              {"on", "offset", "on"}, {"off", "offset", "off"}};
      TraceStatsSum boxedSt;
      for (const Combo& combo : combos) {
        const char* mailbox = combo.mailbox;
        const char* root = combo.root;
        {
          TraceStatsSum scalarSt;
          for (const OctreePath& p : paths) {
            CAPTURE(std::string(p.name));
            CAPTURE(occlusion);
            CAPTURE(std::string(mailbox));
            CAPTURE(std::string(root));
            CAPTURE(std::string(combo.leafBox));
            TraceConfig cfg = base;
            cfg.backend = p.backend;
            cfg.variant = p.variant;
            cfg.params.octreeMargin = "ray";
            cfg.params.octreeMailbox = mailbox;
            cfg.params.octreeRoot = root;
            cfg.params.octreeLeafBox = combo.leafBox;
            std::vector<HitRecord> hits;
            TraceStatsSum st;
            CreateTracer(scene, cfg)->Trace(rays, Tracer::NoTimes(), hits, occlusion, &st);
            CHECK(ref::CheckHits(test::CachedReference(scene), rays, hits, occlusion, Tracer::NoTimes()).wrong == 0);
            // Closest hits: the classic walk's, bit for bit. Any hit: hit or
            // miss the same.
            CHECK(test::CountDiffering(classicHits, hits, occlusion) == 0);
            if (p.backend == Backend::Scalar) {
              scalarSt = st;
              MESSAGE(std::string(RayKindName(kind)), (occlusion ? " any hit" : " closest"), " mailbox ", std::string(mailbox),
                      " leaf boxes ", std::string(combo.leafBox), ": tests per ray, scene margins ",
                      double(classicSt.nIT) / double(rays.size()), ", ray margins ", double(st.nIT) / double(rays.size()));
              CHECK(st.nIT < classicSt.nIT);
              // The leaf boxes spare closest-hit queries tests, not steps
              // (an any-hit query may find its occluder sooner without them:
              // a primitive hit beyond the cell it was met in).
              if (&combo == &combos[1]) boxedSt = st;
              if (&combo == &combos[4] && !occlusion) {
                CHECK(boxedSt.nIT < st.nIT);
                CHECK(boxedSt.nTS == st.nTS);
                CHECK(boxedSt.nLeaves == st.nLeaves);
              }
            }
            if (p.statsAsScalar) {
              CHECK(st.nIT == scalarSt.nIT);
              CHECK(st.nTS == scalarSt.nTS);
              CHECK(st.nLeaves == scalarSt.nLeaves);
            }
          }
        }
      }
    }
  }
}

TEST_CASE("octree: --octree-root: an offset root spares the teapot in a stadium the chains its centre's planes cut, and auto keeps the root of lower cost")
{
  // The stadium's flake sits at the scene's centre: a centred root's mid
  // planes cut it at every level, so rays descend several chains of nodes.
  // At 0.45 of the root no plane passes within a tenth of a cell of it.
  const Scene stadium = GenerateStadium(4);
  AccelParams centre, offset, automatic;
  centre.octreeMargin = offset.octreeMargin = automatic.octreeMargin = "ray";
  centre.octreeRoot = "centre";
  offset.octreeRoot = "offset";
  AccelInfo ci, oi, ai;
  const OctreeData c = BuildOctree(stadium, centre, ci);
  const OctreeData o = BuildOctree(stadium, offset, oi);
  const OctreeData a = BuildOctree(stadium, automatic, ai);
  // The offset root: 1/0.9 of the centred one's side, the scene's centre at
  // 0.45 of it on every axis.
  CHECK(o.header.rootSize > 1.1f * c.header.rootSize);
  CHECK(o.header.rootSize < 1.12f * c.header.rootSize);
  const double costC = OctreeCost(stadium, c), costO = OctreeCost(stadium, o);
  MESSAGE("stadium: cost centre ", costC, ", offset ", costO, "; ", ai.params);
  CHECK(costO < 0.9 * costC);
  CHECK(ai.params.find("root=auto:offset") != std::string::npos);
  CHECK(a.nodes.size() == o.nodes.size());
  CHECK(a.header.rootSize == o.header.rootSize);
  // Fewer steps per primary ray, and the same answers.
  const auto rays = test::MakeRays(stadium, RayKind::Primary, 64);
  std::vector<HitRecord> hits[2];
  TraceStatsSum st[2];
  for (int k = 0; k < 2; ++k) {
    TraceConfig cfg;
    cfg.accel = AccelKind::Octree;
    cfg.backend = Backend::Scalar;
    cfg.stats = true;
    cfg.params = k == 0 ? centre : offset;
    CreateTracer(stadium, cfg)->Trace(rays, Tracer::NoTimes(), hits[k], false, &st[k]);
    CHECK(ref::CheckHits(test::CachedReference(stadium), rays, hits[k], false, Tracer::NoTimes()).wrong == 0);
  }
  MESSAGE("stadium primary steps per ray: centre ", double(st[0].nTS) / double(rays.size()), ", offset ",
          double(st[1].nTS) / double(rays.size()));
  CHECK(double(st[1].nTS) < 0.75 * double(st[0].nTS));
  CHECK(test::CountDiffering(hits[0], hits[1], false) == 0);

  // Gears: the offset root costs more, and auto keeps the centred one.
  const Scene& gears = test::CachedScene(test::SpdPath("gears"));
  AccelInfo gi;
  const OctreeData g = BuildOctree(gears, automatic, gi);
  MESSAGE("gears: ", gi.params);
  CHECK(gi.params.find("root=auto:centre") != std::string::npos);
  AccelInfo gci;
  const OctreeData gc = BuildOctree(gears, centre, gci);
  CHECK(g.header.rootSize == gc.header.rootSize);
  CHECK(g.nodes.size() == gc.nodes.size());

  // Above 2^18 primitives auto compares the roots over a sample and builds
  // the chosen one in full: the sphereflake of 597,873 spheres (at its
  // centre, as the stadium's flake) keeps the offset root, the same tree as
  // --octree-root offset's.
  const Scene flake = GenerateSphereflake(6);
  AccelInfo fi, foi;
  const OctreeData f = BuildOctree(flake, automatic, fi);
  const OctreeData fo = BuildOctree(flake, offset, foi);
  MESSAGE("sphereflake 6: ", fi.params);
  CHECK(fi.params.find("root=auto:offset") != std::string::npos);
  CHECK(fi.params.find("1 in 3 primitives") != std::string::npos);
  CHECK(f.header.rootSize == fo.header.rootSize);
  CHECK(f.nodes.size() == fo.nodes.size());
  CHECK(f.refs == fo.refs);

  // The classic octree keeps its centred root and its description.
  AccelInfo k0, k1;
  AccelParams classicCentre;
  classicCentre.octreeRoot = "centre";
  const OctreeData classic = BuildOctree(stadium, AccelParams{}, k0);
  const OctreeData classicExplicit = BuildOctree(stadium, classicCentre, k1);
  CHECK(classic.header.rootSize == classicExplicit.header.rootSize);
  CHECK(classic.nodes.size() == classicExplicit.nodes.size());
  CHECK(k0.params.find("root=") == std::string::npos);
  AccelParams bad;
  bad.octreeRoot = "middle";
  CHECK_THROWS_AS(BuildOctree(stadium, bad, k0), InputError);
}
