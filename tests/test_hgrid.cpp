// Hierarchical grid (kernels/hgrid.h, host/accel/hgrid_builder.cpp): the
// layout's invariants, refinement where references crowd (the teapot in a
// stadium), and answers against the reference on every CPU backend. The
// cell-plane hard cases (tests/hard/) cover the planes of every level.
#include <algorithm>
#include <cstring>
#include <functional>
#include <string_view>

#include <doctest/doctest.h>

#include "host/accel/accel.h"
#include "host/core/error.h"
#include "host/scene/generate.h"
#include "host/trace/tracer.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

// Checks the flat layout: every grid's offsets ascend inside refs, a cell is
// references (ascending, below the marker bit), or a child marker, the
// number of its references, those, and its large references (a subset);
// every child is named by exactly one cell, lies within the cell grown by the
// cell's margin, and took its references with a margin above 0 and at most
// half its parent's; returns the number of levels.
int CheckLayout(const HGridData& h)
{
  const std::size_t nRefs = h.refs.size();
  std::vector<int> namedBy(h.subs.size(), 0);
  std::function<int(const GridHeader&, int)> walk = [&](const GridHeader& g, int depth) {
    REQUIRE(depth <= CR_HGRID_MAX_DEPTH);
    REQUIRE(std::size_t(g.first) + g.nCells < nRefs);
    int deepest = depth;
    for (std::uint32_t c = 0; c < g.nCells; ++c) {
      const std::uint32_t begin = h.refs[g.first + c], end = h.refs[g.first + c + 1];
      REQUIRE(begin <= end);
      REQUIRE(end <= nRefs);
      std::uint32_t first = begin, nAll = end - begin;
      if (end > begin && (h.refs[begin] & CR_HGRID_CHILD)) {
        const std::uint32_t k = h.refs[begin] & ~CR_HGRID_CHILD;
        REQUIRE(k < h.subs.size());
        REQUIRE(end - begin >= 2u);
        ++namedBy[k];
        const GridHeader& child = h.subs[k];
        CHECK(child.margin > 0.0f);
        CHECK(child.margin <= 0.5f * g.margin);
        nAll = h.refs[begin + 1];
        first += 2;
        REQUIRE(nAll <= end - first);
        const std::uint32_t xyz[3] = {c % g.res[0], (c / g.res[0]) % g.res[1], c / (g.res[0] * g.res[1])};
        for (int a = 0; a < 3; ++a) {
          // The child's box lies within the cell grown by the cell's margin.
          const double lo = double(g.bmin[a] + float(xyz[a]) * g.cellSize[a]);
          const double hi = double(g.bmin[a] + float(xyz[a] + 1) * g.cellSize[a]);
          CHECK(double(child.bmin[a]) >= lo - double(g.margin));
          CHECK(double(child.bmax[a]) <= hi + double(g.margin));
          CHECK(child.bmin[a] < child.bmax[a]);
        }
        deepest = std::max(deepest, walk(child, depth + 1));
      }
      // The references: below the marker bit, ascending; in a child cell,
      // then its large references, ascending, each one of the cell's.
      for (std::uint32_t i = first; i < end; ++i) {
        CHECK((h.refs[i] & CR_HGRID_CHILD) == 0u);
        if (i > first && i != first + nAll) CHECK(h.refs[i - 1] < h.refs[i]);
        if (i >= first + nAll)
          CHECK(std::binary_search(h.refs.begin() + first, h.refs.begin() + first + nAll, h.refs[i]));
      }
    }
    // The distance bytes after the offsets (HGrid_Distance): 0 in a full
    // cell, elsewhere 1 + the least of its 26 neighbours' (at most 255),
    // which only the distance to the nearest full cell satisfies; or all 0
    // (--hgrid-skip off).
    const auto distance = [&](std::uint32_t c) {
      return (h.refs[g.first + g.nCells + 1 + c / 4] >> (8 * (c % 4))) & 0xffu;
    };
    REQUIRE(std::size_t(g.first) + g.nCells + 1 + (g.nCells + 3) / 4 <= nRefs);
    bool allZero = true;
    for (std::uint32_t c = 0; c < g.nCells && allZero; ++c) allZero = distance(c) == 0;
    if (!allZero) {
      const int r[3] = {int(g.res[0]), int(g.res[1]), int(g.res[2])};
      for (std::uint32_t c = 0; c < g.nCells; ++c) {
        const bool full = h.refs[g.first + c] != h.refs[g.first + c + 1];
        if (full) {
          CHECK(distance(c) == 0u);
          continue;
        }
        const int x = int(c % g.res[0]), y = int((c / g.res[0]) % g.res[1]), z = int(c / (g.res[0] * g.res[1]));
        std::uint32_t least = 255;
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = x + dx, ny = y + dy, nz = z + dz;
              if ((dx | dy | dz) == 0 || nx < 0 || ny < 0 || nz < 0 || nx >= r[0] || ny >= r[1] || nz >= r[2])
                continue;
              least = std::min(least, distance(std::uint32_t(nx + r[0] * (ny + r[1] * nz))));
            }
        CHECK(distance(c) == std::min(255u, least + 1));
      }
    }
    return deepest;
  };
  const int levels = 1 + walk(h.header, 0);
  if (levels > 1)
    for (int n : namedBy) CHECK(n == 1);
  return levels;
}

// The CPU paths of the hierarchical grid: the scalar backend and the SIMD
// backend's packet and single-ray walks.
const std::string kPaths[] = {"scalar", "packet", "single"};
TraceConfig PathConfig(std::string_view path)
{
  TraceConfig cfg;
  cfg.backend = path == "scalar" ? Backend::Scalar : Backend::Simd;
  if (cfg.backend == Backend::Simd) cfg.variant = std::string(path);
  cfg.accel = AccelKind::HGrid;
  return cfg;
}

// Checks the hierarchical grid's answers to `rays` against the reference
// and against the uniform grid's, bit for bit (occlusion: hit or miss), on
// scalar and SIMD (its packet and single-ray walks), closest and any hit;
// returns the hits counted over all.
std::size_t CheckAgainstGrid(const Scene& scene, const std::vector<RayRecord>& rays)
{
  std::size_t hits = 0;
  for (const std::string& path : kPaths)
    for (bool occlusion : {false, true}) {
      CAPTURE(path);
      CAPTURE(occlusion);
      TraceConfig cfg = PathConfig(path);
      std::vector<HitRecord> a, b;
      CHECK(test::CheckTracer(scene, cfg, rays, occlusion, &a).wrong == 0);
      cfg.accel = AccelKind::Grid;
      CHECK(test::CheckTracer(scene, cfg, rays, occlusion, &b).wrong == 0);
      CHECK(test::CountDiffering(a, b, occlusion) == 0);
      for (const HitRecord& h : a) hits += h.prim != CR_NO_HIT;
    }
  return hits;
}

}  // namespace

TEST_CASE("hgrid: the teapot in a stadium refines where it crowds, and answers 0 wrong on scalar and simd")
{
  const Scene scene = GenerateStadium(3);
  AccelInfo info;
  // At most 8 references a cell (the default is 16): a hierarchy of three
  // levels or more here, whose layout and answers the test checks.
  AccelParams params;
  params.hgridLeaf = 8;
  const HGridData h = BuildHGrid(scene, params, info);
  const int levels = CheckLayout(h);
  CHECK(levels >= 3);
  const auto rays = test::MakeRays(scene, RayKind::Primary, 64);
  const auto perRay = [&](AccelKind accel) {
    TraceConfig cfg;
    cfg.backend = Backend::Scalar;
    cfg.accel = accel;
    cfg.stats = true;
    auto tracer = CreateTracer(scene, cfg);
    std::vector<HitRecord> hits;
    TraceStatsSum st;
    tracer->Trace(rays, hits, false, &st);
    return double(st.nIT) / double(rays.size());
  };
  // The uniform grid puts the stadium's whole centre in a cell or two.
  const double grid = perRay(AccelKind::Grid), hgrid = perRay(AccelKind::HGrid);
  MESSAGE("tests per ray: grid ", grid, ", hgrid ", hgrid, " (", levels, " levels)");
  CHECK(hgrid * 5.0 < grid);
  CheckAgainstGrid(scene, rays);
}

TEST_CASE("hgrid: skipping empty space by distance gives the walk's answers, bit for bit, in fewer steps")
{
  // The SPD tree: its root grid is flat and its children's boxes hold
  // branches and leaves with empty space between (skip off against on,
  // primary and diffuse rays: 0.69 and 0.70 of the cells visited for
  // closest hits, 0.9 for any hit on diffuse rays). The
  // teapot in a stadium no longer serves: its children's boxes are tight
  // around the teapot, which leaves little empty space to skip.
  const Scene& scene = test::CachedScene(test::SpdPath("tree"));
  AccelParams off;
  off.hgridSkip = "off";
  AccelInfo info;
  CheckLayout(BuildHGrid(scene, off, info));
  CHECK(info.params.find("skip=off") != std::string::npos);
  for (RayKind kind : {RayKind::Primary, RayKind::Diffuse}) {
    const auto rays = test::MakeRays(scene, kind, 64);
    for (const std::string& path : kPaths)
      for (bool occlusion : {false, true}) {
        CAPTURE(path);
        CAPTURE(occlusion);
        std::vector<HitRecord> hits[2];
        TraceStatsSum st[2];
        for (int skip = 0; skip < 2; ++skip) {
          TraceConfig cfg = PathConfig(path);
          cfg.params.hgridSkip = skip ? "on" : "off";
          cfg.stats = true;
          CreateTracer(scene, cfg)->Trace(rays, Tracer::NoTimes(), hits[skip], occlusion, &st[skip]);
          CHECK(ref::CheckHits(test::CachedReference(scene), rays, hits[skip], occlusion, Tracer::NoTimes()).wrong == 0);
        }
        CHECK(test::CountDiffering(hits[0], hits[1], occlusion) == 0);
        CHECK(st[0].nIT == st[1].nIT);
        MESSAGE("cells visited per ray, skip off ", double(st[0].nTS) / double(rays.size()), ", on ",
                double(st[1].nTS) / double(rays.size()));
        // Any-hit walks end at their first occluder, with less space behind them to skip.
        CHECK(double(st[1].nTS) < (occlusion ? 0.95 : 0.8) * double(st[0].nTS));
      }
  }
  AccelParams bad;
  bad.hgridSkip = "maybe";
  CHECK_THROWS_AS(BuildHGrid(scene, bad, info), InputError);
}

TEST_CASE("hgrid: rays from across the stadium test a crowded cell's own references, 0 wrong")
{
  // Rays from the stadium's pillars to the sphereflake: their float walk
  // strays by more than the finest children's margins, so they must test
  // the references of the cells holding those children instead (and the
  // near rays of the first test must walk the children).
  const Scene scene = GenerateStadium(3);
  std::vector<RayRecord> rays;
  for (int i = 0; i < 4096; ++i) {
    const double a = 6.283185307179586 * i / 4096.0;
    const glm::dvec3 from(4400.0 * std::cos(a), 4400.0 * std::sin(a), 30.0 + 7.0 * (i % 13));
    const glm::dvec3 to(0.11 * std::sin(3.0 * i), 0.11 * std::cos(5.0 * i), 0.12 * std::sin(7.0 * i));
    const glm::dvec3 d = to - from;
    rays.push_back(RayRecord{{float(from.x), float(from.y), float(from.z)}, 0.0f,
                             {float(d.x), float(d.y), float(d.z)}, INFINITY});
  }
  CHECK(CheckAgainstGrid(scene, rays) > rays.size());
}

TEST_CASE("hgrid: SPD scenes build a valid layout, and bad densities are input errors")
{
  for (const char* name : {"balls", "teapot", "tree"}) {
    CAPTURE(name);
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    AccelInfo info;
    const HGridData h = BuildHGrid(scene, AccelParams{}, info);
    CHECK(CheckLayout(h) >= 2);
    CHECK(info.refs >= scene.NumUnified());
  }
  const Scene& scene = test::CachedScene(test::SpdPath("tetra"));
  AccelInfo info;
  AccelParams p;
  p.hgridDensity = -1.0;
  CHECK_THROWS_AS(BuildHGrid(scene, p, info), InputError);
  p.hgridDensity = 0.0;
  p.hgridTopDensity = std::nan("");
  CHECK_THROWS_AS(BuildHGrid(scene, p, info), InputError);
  // An empty scene: one empty root cell.
  const HGridData e = BuildHGrid(Scene{}, AccelParams{}, info);
  CHECK(e.header.nRefs == 0u);
}
