// The uniform grid's building blocks, shared by the uniform grid
// (grid_builder.cpp) and every level of the hierarchical grid
// (hgrid_builder.cpp): the resolution rule, the headers (planes of
// Grid_Plane), the padded scene box and the cell epsilon, and the insertion
// of a primitive into every cell its shape meets.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "host/accel/accel.h"
#include "host/prims/prim_host.h"

namespace cr {

namespace grid_plane {
// Grid_Plane() of the kernel, the one definition of the cell planes.
#include "kernels/grid.h"
}  // namespace grid_plane

namespace gridbuild {

// The fixed density that was the default before the cost model
// (ChooseResolutionByCost): the best overall value of
// bench/grid_density_sweep.sh (SPD scenes, primary and shadow rays, scalar
// backend, one thread) in three runs out of three, geometric mean of
// time / best 1.13-1.21 against 1.23-1.37 for 4 and 1.22-1.30 for 8. Scenes
// with a small object on a large ground (tree, balls) want more cells, the
// compact ones 2 to 8: what the cost model tells apart. The hierarchical
// grid's root and its tests use fixed densities; the cost model falls back
// to this one where no candidate fits its memory.
constexpr double kDefaultDensity = 16.0;
constexpr double kMaxDensity = 1024.0;
constexpr int kMaxResAxis = 4096;
constexpr std::uint64_t kMaxCells = std::uint64_t(1) << 28;  // cellStart: 1 GiB
constexpr std::uint64_t kMaxRefs = std::uint64_t(1) << 29;   // refs: 2 GiB
// A cell range larger than this is filled by a nested parallel loop (a huge
// ground polygon must not serialise the build).
constexpr std::uint64_t kNestedCells = 4096;

struct Res {
  int r[3] = {1, 1, 1};
  std::uint64_t Cells() const { return std::uint64_t(r[0]) * std::uint64_t(r[1]) * std::uint64_t(r[2]); }
};

// Woo / Klimaszewski: res_a = extent_a * cbrt(lambda N / volume). An axis of
// zero extent (a flat scene) or one that would get less than half a cell
// gets res 1, and the others share the cells: the 2D area or 1D length
// replaces the volume.
inline Res ChooseResolution(const glm::dvec3& ext, double cells)
{
  bool active[3];
  for (int a = 0; a < 3; ++a) active[a] = ext[a] > 0.0;
  Res res;
  for (int pass = 0; pass < 3; ++pass) {
    int k = 0;
    double measure = 1.0;
    for (int a = 0; a < 3; ++a)
      if (active[a]) {
        ++k;
        measure *= ext[a];
      }
    if (k == 0) return res;
    const double s = std::pow(cells / measure, 1.0 / k);
    bool changed = false;
    for (int a = 0; a < 3; ++a)
      if (active[a] && ext[a] * s < 0.5) {
        active[a] = false;
        changed = true;
      }
    if (changed) continue;
    for (int a = 0; a < 3; ++a) {
      const double r = active[a] ? std::round(ext[a] * s) : 1.0;
      res.r[a] = int(std::clamp(r, 1.0, double(kMaxResAxis)));
    }
    return res;
  }
  return res;
}

inline float RoundDown(double x)
{
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}

// The grid box of a scene (its primitives' boxes): the world bounds padded
// so that no primitive lies on an outer face (a ray grazing the box then
// never meets a surface there), and the cell epsilon.
struct Frame {
  glm::vec3 lo{};
  glm::dvec3 hi{};
  glm::dvec3 ext{};    // the world bounds' extent
  double scale = 0.0;  // max(largest |coordinate|, largest extent)
  // The traversal computes plane crossings t = (plane - o) / d in float and
  // decides which plane comes first from them, so near an edge or corner of
  // a cell it may walk past a sliver of a neighbour that the exact ray
  // crosses. That sliver is within a few float ulps of the planes, relative
  // to the coordinates' magnitude: every cell is tested enlarged by eps, so
  // a primitive that touches a cell within rounding distance is in it.
  double eps = 0.0;
};
inline Frame MakeFrame(const std::vector<Bounds>& boxes)
{
  Bounds world;
  for (const Bounds& box : boxes) world.Extend(box);
  const glm::dvec3 wlo(world.lo), whi(world.hi);
  Frame f;
  f.ext = whi - wlo;
  const double maxExt = std::max(f.ext.x, std::max(f.ext.y, f.ext.z));
  const glm::dvec3 absMax = glm::max(glm::abs(wlo), glm::abs(whi));
  const double mag = std::max(absMax.x, std::max(absMax.y, absMax.z));  // largest |coordinate|
  const double pad = std::max({1e-5 * maxExt, 0x1p-17 * mag, 1e-30});
  f.lo = glm::vec3(RoundDown(wlo.x - pad), RoundDown(wlo.y - pad), RoundDown(wlo.z - pad));
  f.hi = whi + pad;
  f.scale = std::max(mag, maxExt);
  f.eps = 0x1p-18 * f.scale;
  return f;
}

// Cells thinner than about a hundred float ulps of the coordinates would
// blur (planes collapse, the enlargement by eps dominates): caps each axis
// of res over the box [lo, hi]: cells at least minCell * scale wide (4 eps
// by default).
inline void CapResolution(Res& res, const glm::vec3& lo, const glm::dvec3& hi, double scale, double minCell = 0x1p-16)
{
  for (int a = 0; a < 3; ++a) {
    const double span = hi[a] - double(lo[a]);
    const double capD = std::floor(span / (minCell * scale));
    const int cap = int(std::clamp(capD, 1.0, double(kMaxResAxis)));
    res.r[a] = std::min(res.r[a], cap);
  }
}

// The resolution of a uniform grid over f by the cost model of
// grid_cost.cpp (the default): density gets the chosen cells per primitive,
// costs (if given) each candidate's (density, estimated cost per ray).
Res ChooseResolutionByCost(const Scene& scene, const Frame& f, const std::vector<Bounds>& boxes, double& density,
                           std::vector<std::pair<double, double>>* costs = nullptr);

// The header for box [lo, hi] at resolution res: cellSize rounded up until
// the last plane covers hi; bmax is that plane, so the box the traversal
// clips against and the planes it walks agree.
inline GridHeader MakeHeader(const glm::vec3& lo, const glm::dvec3& hi, const Res& res)
{
  GridHeader h{};
  for (int a = 0; a < 3; ++a) {
    h.bmin[a] = lo[a];
    h.res[a] = std::uint32_t(res.r[a]);
    float cs = float((hi[a] - double(lo[a])) / res.r[a]);
    if (!(cs > 0.0f)) cs = std::numeric_limits<float>::min();
    h.cellSize[a] = cs;
    while (double(grid_plane::Grid_Plane(&h, a, res.r[a])) < hi[a])
      h.cellSize[a] = std::nextafter(h.cellSize[a], INFINITY);
    h.bmax[a] = grid_plane::Grid_Plane(&h, a, res.r[a]);
  }
  h.nCells = std::uint32_t(res.Cells());
  return h;
}

// Cells [first, last] on `axis` whose slab, enlarged by eps, meets [lo, hi].
inline void CellRange(const GridHeader& h, int axis, double lo, double hi, double eps, int& first, int& last)
{
  const int n = int(h.res[axis]);
  auto plane = [&](int i) { return double(grid_plane::Grid_Plane(&h, axis, i)); };
  auto guess = [&](double x) {
    double r = std::floor((x - double(h.bmin[axis])) / double(h.cellSize[axis]));
    return int(std::clamp(r, 0.0, double(n - 1)));
  };
  first = guess(lo - eps);
  while (first > 0 && plane(first) + eps >= lo) --first;
  while (first < n - 1 && plane(first + 1) + eps < lo) ++first;
  last = guess(hi + eps);
  while (last < n - 1 && plane(last + 1) - eps <= hi) ++last;
  while (last > 0 && plane(last) - eps > hi) --last;
}

struct Builder {
  explicit Builder(const Scene& s) : scene(s), ranges(s.Ranges()) {}
  const Scene& scene;
  const PrimRanges ranges;
  GridHeader header{};
  double eps = 0.0;
  std::vector<Bounds> boxes;

  // Calls visit(cell) for every cell of `header` primitive g overlaps.
  template <class Visit>
  void ForEachCell(std::uint32_t g, const Visit& visit) const
  {
    ForEachCellOf(header, g, visit);
  }
  // The same for the cells of the grid h, each grown by `grow` (eps by
  // default).
  template <class Visit>
  void ForEachCellOf(const GridHeader& h, std::uint32_t g, const Visit& visit) const
  {
    ForEachCellOf(h, g, eps, visit);
  }
  template <class Visit>
  void ForEachCellOf(const GridHeader& h, std::uint32_t g, double grow, const Visit& visit) const
  {
    int first[3], last[3];
    for (int a = 0; a < 3; ++a) CellRange(h, a, boxes[g].lo[a], boxes[g].hi[a], grow, first[a], last[a]);
    auto slice = [&](int z) {
      glm::dvec3 lo, hi;
      lo.z = double(grid_plane::Grid_Plane(&h, 2, z)) - grow;
      hi.z = double(grid_plane::Grid_Plane(&h, 2, z + 1)) + grow;
      for (int y = first[1]; y <= last[1]; ++y) {
        lo.y = double(grid_plane::Grid_Plane(&h, 1, y)) - grow;
        hi.y = double(grid_plane::Grid_Plane(&h, 1, y + 1)) + grow;
        for (int x = first[0]; x <= last[0]; ++x) {
          lo.x = double(grid_plane::Grid_Plane(&h, 0, x)) - grow;
          hi.x = double(grid_plane::Grid_Plane(&h, 0, x + 1)) + grow;
          if (PrimOverlapsBox(scene, ranges, g, lo, hi))
            visit(std::uint32_t(x) + h.res[0] * (std::uint32_t(y) + h.res[1] * std::uint32_t(z)));
        }
      }
    };
    const std::uint64_t volume = std::uint64_t(last[0] - first[0] + 1) * std::uint64_t(last[1] - first[1] + 1) *
                                 std::uint64_t(last[2] - first[2] + 1);
    if (volume > kNestedCells && last[2] > first[2]) {
      tbb::parallel_for(first[2], last[2] + 1, [&](int z) { slice(z); });
    } else {
      for (int z = first[2]; z <= last[2]; ++z) slice(z);
    }
  }

  // Per-cell counts into count[0..nCells); returns the total.
  std::uint64_t Count(std::vector<std::uint32_t>& count) const
  {
    const auto n = static_cast<std::uint32_t>(boxes.size());
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n), [&](const tbb::blocked_range<std::uint32_t>& r) {
      for (std::uint32_t g = r.begin(); g != r.end(); ++g)
        ForEachCell(g, [&](std::uint32_t c) {
          std::atomic_ref<std::uint32_t>(count[c]).fetch_add(1, std::memory_order_relaxed);
        });
    });
    std::uint64_t total = 0;  // a cell holds at most n < 2^32 references
    for (std::uint32_t k : count) total += k;
    return total;
  }
};

}  // namespace gridbuild

}  // namespace cr
