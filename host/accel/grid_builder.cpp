// Uniform grid builder. Resolution after Woo (Graphics Gems, "Ray tracing
// polygons using spatial subdivision") and Klimaszewski: about lambda * N
// cells, cubic as far as the scene box allows, lambda chosen per scene by a
// cost model (grid_cost.cpp) unless --grid-density fixes it. Each primitive goes into every
// cell its shape overlaps (host/prims/), in two parallel passes over the
// primitives (count, then fill) into the compressed row layout of GridHeader
// (types.h), references sorted ascending in each cell.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <new>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "host/accel/accel.h"
#include "host/accel/grid_build.h"
#include "host/prims/prim_host.h"
#include "host/core/error.h"

namespace cr {

using namespace gridbuild;

GridData BuildGrid(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  double density = params.gridDensity;
  if (!std::isfinite(density) || density < 0.0)
    throw InputError(fmt::format("--grid-density {} is not a finite number >= 0", density));
  const bool byCost = density == 0.0;
  if (density > kMaxDensity) {
    Warn(fmt::format("--grid-density {} is too large: using {}", density, kMaxDensity));
    density = kMaxDensity;
  }

  GridData out;
  const std::uint32_t n = scene.NumUnified();
  if (n == 0) {
    // One empty cell; Grid_Trace returns at once when nRefs == 0.
    GridHeader& h = out.header;
    for (int a = 0; a < 3; ++a) {
      h.res[a] = 1;
      h.cellSize[a] = 1.0f;
      h.bmax[a] = 1.0f;
    }
    h.nCells = 1;
    out.cellStart = {0, 0};
    info.nodes = info.leaves = info.emptyLeaves = 1;
    info.bytes = sizeof(GridHeader) + 2 * sizeof(std::uint32_t);
    info.params = "density=0 res=1x1x1";
    return out;
  }

  Builder b(scene);
  b.boxes.resize(n);
  tbb::parallel_for(std::uint32_t(0), n, [&](std::uint32_t g) { b.boxes[g] = scene.UnifiedBounds(g); });
  const Frame f = MakeFrame(b.boxes);
  b.eps = f.eps;
  Res res;
  if (byCost) {
    res = ChooseResolutionByCost(scene, f, b.boxes, density);
  } else {
    res = ChooseResolution(f.ext, density * double(n));
    CapResolution(res, f.lo, f.hi, f.scale);
  }
  if (res.Cells() > kMaxCells) {
    const Res asked = res;
    const double shrink = std::cbrt(double(kMaxCells) / double(res.Cells()));
    for (int a = 0; a < 3; ++a) res.r[a] = std::max(1, int(std::floor(res.r[a] * shrink)));
    while (res.Cells() > kMaxCells)
      for (int a = 0; a < 3; ++a) res.r[a] = std::max(1, res.r[a] - 1);
    Warn(fmt::format("grid: {}x{}x{} cells exceed the limit of {}: using {}x{}x{}", asked.r[0], asked.r[1], asked.r[2],
                     kMaxCells, res.r[0], res.r[1], res.r[2]));
  }

  std::uint64_t total = 0;
  try {
    for (;;) {
      b.header = MakeHeader(f.lo, f.hi, res);
      out.cellStart.assign(b.header.nCells + std::size_t(1), 0u);
      total = b.Count(out.cellStart);
      if (total <= kMaxRefs || res.Cells() == 1) break;
      const Res asked = res;
      for (int a = 0; a < 3; ++a) res.r[a] = std::max(1, res.r[a] / 2);
      Warn(fmt::format("grid: {} references at {}x{}x{} exceed the limit of {}: using {}x{}x{}", total, asked.r[0],
                       asked.r[1], asked.r[2], kMaxRefs, res.r[0], res.r[1], res.r[2]));
    }
    if (total >= std::uint64_t(UINT32_MAX)) throw RuntimeError(fmt::format("grid: {} references do not fit 32-bit indices", total));

    // Counts -> starts (exclusive scan); the fill pass then advances each
    // start to its cell's end, which is the next cell's start: shift back.
    std::vector<std::uint32_t>& start = out.cellStart;
    const std::uint32_t nCells = b.header.nCells;
    std::uint32_t sum = 0;
    for (std::uint32_t c = 0; c < nCells; ++c) {
      const std::uint32_t k = start[c];
      start[c] = sum;
      sum += k;
    }
    start[nCells] = sum;
    out.refs.resize(total);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n), [&](const tbb::blocked_range<std::uint32_t>& r) {
      for (std::uint32_t g = r.begin(); g != r.end(); ++g)
        b.ForEachCell(g, [&](std::uint32_t c) {
          out.refs[std::atomic_ref<std::uint32_t>(start[c]).fetch_add(1, std::memory_order_relaxed)] = g;
        });
    });
    std::copy_backward(start.begin(), start.begin() + nCells, start.begin() + nCells + 1);
    start[0] = 0;
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, nCells, 1024), [&](const tbb::blocked_range<std::uint32_t>& r) {
      for (std::uint32_t c = r.begin(); c != r.end(); ++c)
        std::sort(out.refs.begin() + start[c], out.refs.begin() + start[c + 1]);
    });
  } catch (const std::bad_alloc&) {
    throw RuntimeError(fmt::format("grid: out of memory for {}x{}x{} cells", res.r[0], res.r[1], res.r[2]));
  }
  b.header.nRefs = std::uint32_t(total);
  out.header = b.header;

  std::uint64_t empty = 0;
  for (std::uint32_t c = 0; c < b.header.nCells; ++c) empty += out.cellStart[c] == out.cellStart[c + 1];
  info.nodes = b.header.nCells;
  info.leaves = b.header.nCells;
  info.emptyLeaves = empty;
  info.refs = total;
  info.bytes = sizeof(GridHeader) + out.cellStart.size() * sizeof(std::uint32_t) + out.refs.size() * sizeof(std::uint32_t);
  info.params = fmt::format("density={}{} res={}x{}x{}", density, byCost ? " (cost model)" : "", res.r[0], res.r[1],
                            res.r[2]);
  return out;
}

}  // namespace cr
