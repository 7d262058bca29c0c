// Two-level grid builder (Kalojanov, Billeter & Slusallek 2011): a coarse
// uniform grid over the scene (the uniform grid's builder at
// --grid2-top-density cells per primitive), then in every non-empty top cell
// a uniform grid of its own with about --grid2-density cells per reference,
// cubic as far as the cell allows (the uniform grid's resolution rule). A
// sub-grid's first planes are its top cell's lower planes, bit for bit; its
// cell size is rounded up until its last planes reach the cell's upper
// planes (MakeHeader), so the sub-grids cover the top grid without gaps. A
// reference of a top cell goes into every sub-cell its shape meets, each
// grown by the uniform grid's epsilon (host/accel/grid_build.h). Top cells
// are built in parallel; each fills its sub-cells in ascending reference
// order, so the references of every sub-cell come sorted.
#include <algorithm>
#include <cmath>
#include <new>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "host/accel/accel.h"
#include "host/accel/grid_build.h"
#include "host/core/error.h"

namespace cr {

using namespace gridbuild;

namespace {

// Defaults (0 on the command line): bench/grid2_param_sweep.sh, docs/ACCEL.md.
constexpr double kDefaultTopDensity = 1.0 / 16.0;
constexpr double kDefaultSubDensity = 4.0;
constexpr double kMaxSubDensity = 1024.0;
// A sub-grid holds at most this many cells (a top cell holding most of the
// scene gets no more than a uniform grid would).
constexpr std::uint64_t kMaxSubCells = std::uint64_t(1) << 24;

double Density(double d, double def, double max, const char* option)
{
  if (!std::isfinite(d) || d < 0.0) throw InputError(fmt::format("{} {} is not a finite number >= 0", option, d));
  if (d == 0.0) return def;
  if (d > max) {
    Warn(fmt::format("{} {} is too large: using {}", option, d, max));
    return max;
  }
  return d;
}

// One top cell's sub-grid: its header (first and nRefs still relative), its
// cell offsets (relative to its first reference) and its references.
struct Sub {
  GridHeader header{};
  std::vector<std::uint32_t> start;
  std::vector<std::uint32_t> refs;
};

}  // namespace

Grid2Data BuildGrid2(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  const double topDensity = Density(params.grid2TopDensity, kDefaultTopDensity, kMaxDensity, "--grid2-top-density");
  const double subDensity = Density(params.grid2Density, kDefaultSubDensity, kMaxSubDensity, "--grid2-density");

  AccelParams topParams;
  topParams.gridDensity = topDensity;
  AccelInfo topInfo;
  GridData top = BuildGrid(scene, topParams, topInfo);

  Grid2Data out;
  out.header = top.header;
  const GridHeader th = top.header;
  const std::uint32_t n = scene.NumUnified();
  const std::uint32_t nTop = th.nCells;
  std::vector<Sub> subs(nTop);
  if (n != 0) {
    Builder b(scene);
    b.boxes.resize(n);
    tbb::parallel_for(std::uint32_t(0), n, [&](std::uint32_t g) { b.boxes[g] = scene.UnifiedBounds(g); });
    const Frame f = MakeFrame(b.boxes);
    b.eps = f.eps;
    try {
      tbb::parallel_for(std::uint32_t(0), nTop, [&](std::uint32_t c) {
        const std::uint32_t begin = top.cellStart[c], end = top.cellStart[c + 1];
        if (begin == end) return;
        const std::uint32_t xyz[3] = {c % th.res[0], (c / th.res[0]) % th.res[1], c / (th.res[0] * th.res[1])};
        glm::vec3 lo;
        glm::dvec3 hi;
        for (int a = 0; a < 3; ++a) {
          lo[a] = grid_plane::Grid_Plane(&th, a, int(xyz[a]));
          hi[a] = double(grid_plane::Grid_Plane(&th, a, int(xyz[a]) + 1));
        }
        Res res = ChooseResolution(hi - glm::dvec3(lo), subDensity * double(end - begin));
        CapResolution(res, lo, hi, f.scale);
        while (res.Cells() > kMaxSubCells)
          for (int a = 0; a < 3; ++a) res.r[a] = std::max(1, res.r[a] / 2);
        Sub& s = subs[c];
        s.header = MakeHeader(lo, hi, res);
        s.start.assign(s.header.nCells + std::size_t(1), 0u);
        for (std::uint32_t i = begin; i < end; ++i)
          b.ForEachCellOf(s.header, top.refs[i], [&](std::uint32_t k) { ++s.start[k]; });
        std::uint32_t sum = 0;
        for (std::uint32_t k = 0; k < s.header.nCells; ++k) {
          const std::uint32_t m = s.start[k];
          s.start[k] = sum;
          sum += m;
        }
        s.start[s.header.nCells] = sum;
        s.refs.resize(sum);
        std::vector<std::uint32_t> fill(s.start.begin(), s.start.end() - 1);
        for (std::uint32_t i = begin; i < end; ++i) {
          const std::uint32_t g = top.refs[i];
          b.ForEachCellOf(s.header, g, [&](std::uint32_t k) { s.refs[fill[k]++] = g; });
        }
        s.header.nRefs = sum;
      });
    } catch (const std::bad_alloc&) {
      throw RuntimeError("grid2: out of memory for the sub-grids");
    }
  }
  top = GridData{};  // out.header keeps the top grid's header

  // Layout: every sub-grid's cell offsets, then every sub-grid's references.
  std::uint64_t nOffsets = 0, nRefs = 0, nSubCells = 0, emptySubCells = 0, emptyTop = 0;
  for (const Sub& s : subs) {
    if (s.header.nRefs == 0) {
      ++emptyTop;
      continue;
    }
    nOffsets += s.start.size();
    nRefs += s.refs.size();
    nSubCells += s.header.nCells;
  }
  if (nOffsets + nRefs >= std::uint64_t(UINT32_MAX))
    throw RuntimeError(fmt::format("grid2: {} references and cell offsets do not fit 32-bit indices", nOffsets + nRefs));
  try {
    out.subs.assign(nTop, GridHeader{});
    out.refs.resize(nOffsets + nRefs);
  } catch (const std::bad_alloc&) {
    throw RuntimeError(fmt::format("grid2: out of memory for {} references", nOffsets + nRefs));
  }
  std::vector<std::uint64_t> offsetAt(nTop), refAt(nTop);
  std::uint64_t o = 0, r = nOffsets;
  for (std::uint32_t c = 0; c < nTop; ++c) {
    offsetAt[c] = o;
    refAt[c] = r;
    if (subs[c].header.nRefs == 0) continue;
    o += subs[c].start.size();
    r += subs[c].refs.size();
  }
  tbb::parallel_for(std::uint32_t(0), nTop, [&](std::uint32_t c) {
    Sub& s = subs[c];
    if (s.header.nRefs == 0) return;
    s.header.first = std::uint32_t(offsetAt[c]);
    out.subs[c] = s.header;
    for (std::size_t k = 0; k < s.start.size(); ++k) out.refs[offsetAt[c] + k] = std::uint32_t(refAt[c] + s.start[k]);
    std::copy(s.refs.begin(), s.refs.end(), out.refs.begin() + std::ptrdiff_t(refAt[c]));
  });
  for (const Sub& s : subs)
    if (s.header.nRefs != 0)
      for (std::uint32_t k = 0; k < s.header.nCells; ++k) emptySubCells += s.start[k] == s.start[k + 1];
  out.header.nRefs = std::uint32_t(nRefs);
  out.header.first = 0;
  if (out.subs.empty()) out.subs.assign(1, GridHeader{});

  info.nodes = nTop + nSubCells;
  info.leaves = emptyTop + nSubCells;
  info.emptyLeaves = emptyTop + emptySubCells;
  info.refs = nRefs;
  info.bytes = sizeof(GridHeader) * (1 + out.subs.size()) + out.refs.size() * sizeof(std::uint32_t);
  info.params = fmt::format("top={} sub={} res={}x{}x{} subcells={}", topDensity, subDensity, out.header.res[0],
                            out.header.res[1], out.header.res[2], nSubCells);
  return out;
}

}  // namespace cr
