// Hierarchical grid builder (Jevans & Wyvill 1989; the two-level grid of
// Kalojanov, Billeter & Slusallek 2011 is its first level): a root uniform
// grid over the scene (the uniform grid's builder at --hgrid-top-density
// cells per primitive), then in every cell holding more than --hgrid-leaf
// references a uniform grid of its own with about --hgrid-density cells per
// reference, cubic as far as its box allows (the uniform grid's resolution
// rule), and so on down to CR_HGRID_MAX_DEPTH levels below the root. A
// child's box is that of the references it takes within the cell (grown by
// half the cell's margin): the cell's large references (a ground, a wall)
// stay in the cell where that is cheaper, and the teapot in a stadium's cell
// gets a child over the teapot alone (BuildChild). A child is kept only
// where the surface area heuristic finds it cheaper than the cell's own
// tests, so huge or overlapping primitives that every child cell would hold
// again stay in their cell. A child's cell size is rounded up until its last
// planes reach its box's upper side (MakeHeader), by a few ulps that the
// parent's margin covers. A reference goes into every cell its shape meets
// at every level, each grown by its grid's margin: the
// uniform grid's epsilon at the root (host/accel/grid_build.h), a part of
// the cell size in a child (kMarginPerCell; why a child's margin may be
// smaller than the root's: kernels/hgrid.h). Cells are filled in ascending
// reference order, so their references come sorted. The root's cells are
// refined in parallel. Each grid's empty cells get their distance to the
// nearest full one, by which the walk skips empty space (WriteDistances;
// --hgrid-skip off writes zeros).
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <new>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "host/accel/accel.h"
#include "host/accel/grid_build.h"
#include "host/core/error.h"

namespace cr {

using namespace gridbuild;

namespace {

// Defaults (0 on the command line): bench/hgrid_param_sweep.py, docs/ACCEL.md.
// The child density was 2 until children took margins of their own; with
// them, 1 is faster (SIMD, one thread, 256^2 primary and diffuse rays:
// geometric mean of time / the better of the two 1.03 against 1.07 on the 11
// SPD scenes, 1.01 against 1.07 on bunny, sponza, dragon100k; 1.5x faster on
// the teapot in a stadium) and smaller.
constexpr double kDefaultTopDensity = 0.25;
constexpr double kDefaultSubDensity = 1.0;
constexpr double kMaxSubDensity = 1024.0;
// A cell with more references than this gets a child grid (--hgrid-leaf).
// 16 rather than 8 since the children's boxes are tight (a descent costs a
// box test, an entry and a return): 14 scenes (the SPD scenes, the meshes,
// the teapot in a stadium), primary and diffuse rays, one thread, SIMD
// 7% faster in geometric mean (12 at 3%, 24 at 5%, 32 at 7%; stadium
// primary 11%), OpenCL the same (0.98, within its noise); smaller.
constexpr int kDefaultLeafRefs = 16;
// A child's cells are at least 2^-14 of its coordinates' magnitude wide
// (512 float ulps: planes stay distinct), and take their references with a
// margin of 1/32 of their smallest side (a surface meets about 13% more of
// them than with none), at most the parent's margin. A ray walks a child
// while its reach (kernels/hgrid.h HGrid_Reach) is within that margin: up to
// 2^16 cell sides from its origin.
constexpr double kMinChildCellRel = 0x1p-14;
constexpr double kMarginPerCell = 1.0 / 32.0;
// The cost of a cell step against a primitive test, and the most copies of
// a cell's references a child may hold (BuildChild).
constexpr double kStepCost = 1.0;
constexpr std::uint64_t kMaxCopies = 8;
// A child grid holds at most this many cells.
constexpr std::uint64_t kMaxChildCells = std::uint64_t(1) << 22;
// A reference whose box spans this part of a cell's side on two axes is one
// the cell keeps for every ray (IsLargeIn).
constexpr double kLargeSpan = 0.5;
// The child over every reference of a cell that has large ones is built
// only where its surface area cost is below this part of the child's that
// leaves them in the cell (BuildChild). The heuristic assumes rays spread
// evenly over the cell; those of a scene mostly come near its surfaces, and
// a cell's large references are mostly in the ray's mailbox already (they
// span its neighbours too). SIMD, one thread, 65,536 primary and diffuse
// rays of teapot, gears, balls, tree, rings, bunny and the teapot in a
// stadium, Mrays/s at 1 / 0.5 / 0 (always separate): stadium primary 5.17 /
// 6.24 / 6.22, diffuse 2.92 / 3.26 / 3.28; gears 6.21 / 6.26 / 5.86 and
// 3.65 / 3.38 / 3.24; bunny 4.58 / 4.93 / 4.98 and 1.75 / 1.83 / 1.88; the
// others within 6% of each other.
constexpr double kKeepLargeBias = 0.5;

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

// One grid while building: its header, cell offsets into `items`, each
// cell's references, its child grids, and for each cell 0 or 1 + the
// ordinal in `children` of its child (empty while it has none); `node` is
// its index among all grids, the root 0 (Collect).
struct GridBuild {
  GridHeader h{};
  std::vector<std::uint32_t> start;
  std::vector<std::uint32_t> items;
  std::vector<std::unique_ptr<GridBuild>> children;
  std::vector<std::uint32_t> childAt;
  std::size_t node = 0;
  // As a child: the references its parent cell keeps for every ray (the
  // cell's large references, ascending; BuildChild).
  std::vector<std::uint32_t> parentLarge;

  void SetChild(std::uint32_t c, std::unique_ptr<GridBuild> child)
  {
    if (childAt.empty()) childAt.assign(h.nCells, 0u);
    children.push_back(std::move(child));
    childAt[c] = std::uint32_t(children.size());
  }
  const GridBuild* ChildOf(std::uint32_t c) const
  {
    return childAt.empty() || childAt[c] == 0 ? nullptr : children[childAt[c] - 1].get();
  }
};

struct Context {
  const Builder& b;
  const Frame& f;
  double subDensity;
  std::uint32_t leafRefs;
};

void Refine(const Context& cx, GridBuild& grid, std::uint32_t c, int depth);

// The box of cell c of grid h: float lower planes, upper planes in double.
void CellBox(const GridHeader& h, std::uint32_t c, glm::vec3& lo, glm::dvec3& hi)
{
  const std::uint32_t xyz[3] = {c % h.res[0], (c / h.res[0]) % h.res[1], c / (h.res[0] * h.res[1])};
  for (int a = 0; a < 3; ++a) {
    lo[a] = grid_plane::Grid_Plane(&h, a, int(xyz[a]));
    hi[a] = double(grid_plane::Grid_Plane(&h, a, int(xyz[a]) + 1));
  }
}

// Whether a primitive with box b is one of the large references of cell
// [lo, hi]: its box spans at least half the cell on two axes or more (a
// ground, a wall). The cell keeps those for every ray rather than handing
// them to its child, whose box then shrinks to what is left.
bool IsLargeIn(const Bounds& b, const glm::vec3& lo, const glm::dvec3& hi)
{
  int spans = 0;
  for (int a = 0; a < 3; ++a) {
    const double side = hi[a] - double(lo[a]);
    const double in = std::min(double(b.hi[a]), hi[a]) - std::max(double(b.lo[a]), double(lo[a]));
    spans += in >= kLargeSpan * side;
  }
  return spans >= 2;
}

// A child grid for cell [lo, hi] over the references `small` (the rest of
// the cell's n references, `large`, stay in the cell), with its counts per
// cell in start and its surface area cost (BuildChild); nullptr where it
// would separate nothing.
struct ChildPlan {
  std::unique_ptr<GridBuild> g;
  double cost = INFINITY;
  std::uint64_t sum = 0;
};
ChildPlan PlanChild(const Context& cx, const glm::vec3& lo, const glm::dvec3& hi, const std::vector<std::uint32_t>& small,
                    std::size_t nLarge, double parentMargin)
{
  ChildPlan plan;
  if (small.empty()) return plan;
  // The child's box: its references' boxes within the cell grown by half the
  // parent's margin, grown by a quarter of that (never flat), within the same.
  const double half = 0.5 * parentMargin;
  glm::dvec3 blo(INFINITY), bhi(-INFINITY);
  for (const std::uint32_t r : small) {
    const Bounds& b = cx.b.boxes[r];
    for (int a = 0; a < 3; ++a) {
      blo[a] = std::min(blo[a], std::max(double(b.lo[a]), double(lo[a]) - half));
      bhi[a] = std::max(bhi[a], std::min(double(b.hi[a]), hi[a] + half));
    }
  }
  glm::vec3 glo;
  glm::dvec3 ghi;
  for (int a = 0; a < 3; ++a) {
    const double l = std::max(std::min(blo[a], hi[a]) - 0.5 * half, double(lo[a]) - half);
    const double h = std::min(std::max(bhi[a], double(lo[a])) + 0.5 * half, hi[a] + half);
    glo[a] = RoundDown(l);
    if (!(double(glo[a]) >= double(lo[a]) - half)) glo[a] = std::nextafter(glo[a], INFINITY);
    ghi[a] = std::max(h, double(glo[a]));
  }
  const std::uint32_t ns = std::uint32_t(small.size());
  Res res = ChooseResolution(ghi - glm::dvec3(glo), cx.subDensity * double(ns));
  const glm::dvec3 absMax = glm::max(glm::abs(glm::dvec3(glo)), glm::abs(ghi));
  CapResolution(res, glo, ghi, std::max(absMax.x, std::max(absMax.y, absMax.z)), kMinChildCellRel);
  while (res.Cells() > kMaxChildCells)
    for (int a = 0; a < 3; ++a) res.r[a] = std::max(1, res.r[a] / 2);
  if (res.Cells() == 1) return plan;
  auto g = std::make_unique<GridBuild>();
  g->h = MakeHeader(glo, ghi, res);
  // The margin, from the sides of the axes the child divides; its last
  // planes overshoot its box by a few ulps, which with half the parent's
  // margin must stay within the parent's margin (kernels/hgrid.h).
  double cellMin = INFINITY, overshoot = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (res.r[a] > 1) cellMin = std::min(cellMin, double(g->h.cellSize[a]));
    overshoot = std::max(overshoot, double(g->h.bmax[a]) - ghi[a]);
  }
  if (!(2.0 * overshoot < half)) return plan;
  const double margin = double(RoundDown(std::min(half, std::max(kMarginPerCell * cellMin, 2.0 * overshoot))));
  g->h.margin = float(margin);
  const std::uint32_t nCells = g->h.nCells;
  g->start.assign(nCells + std::size_t(1), 0u);
  for (const std::uint32_t r : small) cx.b.ForEachCellOf(g->h, r, margin, [&](std::uint32_t k) { ++g->start[k]; });
  std::uint64_t sum = 0;
  for (std::uint32_t k = 0; k < nCells; ++k) {
    const std::uint32_t m = g->start[k];
    g->start[k] = std::uint32_t(sum);
    sum += m;
  }
  g->start[nCells] = std::uint32_t(sum);
  // The surface area heuristic of a grid: a ray through the cell tests the
  // large references, enters each child cell with probability about the
  // ratio of their areas (all child cells alike), and pays a step there and
  // a test per reference. A child that copies its references more than
  // kMaxCopies times (huge or overlapping primitives that every child cell
  // would hold again) is none.
  if (sum > kMaxCopies * std::uint64_t(ns)) return plan;
  const auto area = [](const glm::dvec3& e) { return e.x * e.y + e.y * e.z + e.z * e.x; };
  const double ratio = area(glm::dvec3(g->h.cellSize[0], g->h.cellSize[1], g->h.cellSize[2])) /
                       area(glm::dvec3(hi) - glm::dvec3(lo));
  plan.cost = double(nLarge) + ratio * (kStepCost * double(nCells) + double(sum));
  plan.sum = sum;
  plan.g = std::move(g);
  return plan;
}

// A child grid for cell [lo, hi], whose references `refs` (ascending) the
// cell took with margin parentMargin, at level `depth`; nullptr when it
// would separate nothing or cost more than the cell's own tests (the
// surface area heuristic of PlanChild). Two children are planned: over
// every reference, and over all but the cell's large references
// (IsLargeIn), which the cell then keeps for every ray, and the child's box
// shrinks to what is left (a ray that misses that box skips the child:
// kernels/hgrid.h); the second is built unless the first costs less than
// kKeepLargeBias of it. The child's parentLarge lists the large references
// its cell keeps.
std::unique_ptr<GridBuild> BuildChild(const Context& cx, const glm::vec3& lo, const glm::dvec3& hi,
                                      const std::uint32_t* refs, std::uint32_t n, int depth, double parentMargin)
{
  std::vector<std::uint32_t> large, small;
  for (std::uint32_t i = 0; i < n; ++i) (IsLargeIn(cx.b.boxes[refs[i]], lo, hi) ? large : small).push_back(refs[i]);
  ChildPlan plan;
  if (!large.empty()) {
    plan = PlanChild(cx, lo, hi, small, large.size(), parentMargin);
    ChildPlan all = PlanChild(cx, lo, hi, std::vector<std::uint32_t>(refs, refs + n), 0, parentMargin);
    if (all.cost < kKeepLargeBias * plan.cost) {
      plan = std::move(all);
      small.assign(refs, refs + n);
      large.clear();
    }
  } else {
    plan = PlanChild(cx, lo, hi, small, 0, parentMargin);
  }
  if (!(plan.cost < double(n))) return nullptr;
  std::unique_ptr<GridBuild> g = std::move(plan.g);
  const std::uint64_t sum = plan.sum;
  const double margin = double(g->h.margin);
  g->items.resize(sum);
  std::vector<std::uint32_t> fill(g->start.begin(), g->start.end() - 1);
  for (const std::uint32_t r : small) cx.b.ForEachCellOf(g->h, r, margin, [&](std::uint32_t k) { g->items[fill[k]++] = r; });
  g->parentLarge = std::move(large);
  const std::uint32_t nCells = g->h.nCells;
  g->h.nRefs = std::uint32_t(sum);
  if (depth < CR_HGRID_MAX_DEPTH)
    for (std::uint32_t k = 0; k < nCells; ++k) Refine(cx, *g, k, depth);
  return g;
}

// Gives cell c of `grid` (at level depth - 1) a child grid where it holds
// more than --hgrid-leaf references and the child separates them.
void Refine(const Context& cx, GridBuild& grid, std::uint32_t c, int depth)
{
  const std::uint32_t begin = grid.start[c], end = grid.start[c + 1];
  if (end - begin <= cx.leafRefs) return;
  glm::vec3 lo;
  glm::dvec3 hi;
  CellBox(grid.h, c, lo, hi);
  std::unique_ptr<GridBuild> child =
      BuildChild(cx, lo, hi, grid.items.data() + begin, end - begin, depth + 1, double(grid.h.margin));
  if (child) grid.SetChild(c, std::move(child));
}

// The distance bytes of kernels/hgrid.h (HGrid_Distance): for each empty
// cell the distance, in cells and max norm, to the nearest cell with
// references or a child, at most 255 (0 for those), packed four to a word
// after the grid's cell offsets. Two raster passes over the 26 neighbours
// (a chamfer transform with unit weights, exact for the max norm).
void WriteDistances(const GridBuild& g, std::uint32_t* words)
{
  const int rx = int(g.h.res[0]), ry = int(g.h.res[1]), rz = int(g.h.res[2]);
  const std::uint32_t n = g.h.nCells;
  std::vector<std::uint8_t> d(n);
  for (std::uint32_t c = 0; c < n; ++c) d[c] = g.start[c + 1] != g.start[c] || g.ChildOf(c) ? 0 : 255;
  const auto pass = [&](int dir) {
    const int z0 = dir > 0 ? 0 : rz - 1, y0 = dir > 0 ? 0 : ry - 1, x0 = dir > 0 ? 0 : rx - 1;
    for (int z = z0; z >= 0 && z < rz; z += dir)
      for (int y = y0; y >= 0 && y < ry; y += dir)
        for (int x = x0; x >= 0 && x < rx; x += dir) {
          std::uint8_t& v = d[std::size_t(x) + std::size_t(rx) * (std::size_t(y) + std::size_t(ry) * z)];
          if (v == 0) continue;
          // The 13 neighbours the pass has already visited: those before
          // this cell in its order (dz, dy, dx lexicographically).
          for (int dz = -1; dz <= 0; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0))) continue;
                const int nx = x + dir * dx, ny = y + dir * dy, nz = z + dir * dz;
                if (nx < 0 || ny < 0 || nz < 0 || nx >= rx || ny >= ry || nz >= rz) continue;
                const std::uint8_t w = d[std::size_t(nx) + std::size_t(rx) * (std::size_t(ny) + std::size_t(ry) * nz)];
                if (w + 1 < v) v = std::uint8_t(w + 1);
              }
        }
  };
  pass(1);
  pass(-1);
  for (std::uint32_t c = 0; c < n; c += 4) {
    std::uint32_t w = 0;
    for (std::uint32_t k = 0; k < 4 && c + k < n; ++k) w |= std::uint32_t(d[c + k]) << (8 * k);
    words[c / 4] = w;
  }
}

// Every grid, depth first, the root at 0 (GridBuild::node).
void Collect(GridBuild& g, std::vector<GridBuild*>& all)
{
  g.node = all.size();
  all.push_back(&g);
  for (auto& c : g.children) Collect(*c, all);
}

}  // namespace

HGridData BuildHGrid(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  const double topDensity = Density(params.hgridTopDensity, kDefaultTopDensity, kMaxDensity, "--hgrid-top-density");
  const double subDensity = Density(params.hgridDensity, kDefaultSubDensity, kMaxSubDensity, "--hgrid-density");
  if (params.hgridLeaf < 0) throw InputError(fmt::format("--hgrid-leaf {} is negative", params.hgridLeaf));
  const std::uint32_t leafRefs = std::uint32_t(params.hgridLeaf == 0 ? kDefaultLeafRefs : params.hgridLeaf);
  if (!params.hgridSkip.empty() && params.hgridSkip != "on" && params.hgridSkip != "off")
    throw InputError(fmt::format("--hgrid-skip {}: use on or off", params.hgridSkip));
  const bool skip = params.hgridSkip != "off";

  AccelParams topParams;
  topParams.gridDensity = topDensity;
  AccelInfo topInfo;
  GridData top = BuildGrid(scene, topParams, topInfo);
  GridBuild root;
  root.h = top.header;
  root.start = std::move(top.cellStart);
  root.items = std::move(top.refs);

  const std::uint32_t n = scene.NumUnified();
  if (n != 0) {
    Builder b(scene);
    b.boxes.resize(n);
    tbb::parallel_for(std::uint32_t(0), n, [&](std::uint32_t g) { b.boxes[g] = scene.UnifiedBounds(g); });
    const Frame f = MakeFrame(b.boxes);
    b.eps = f.eps;
    const Context cx{b, f, subDensity, leafRefs};
    root.h.margin = RoundDown(f.eps);
    // Children are built per root cell in parallel, then numbered in cell
    // order (deterministic whatever the threads).
    std::vector<std::unique_ptr<GridBuild>> perCell(root.h.nCells);
    try {
      tbb::parallel_for(std::uint32_t(0), root.h.nCells, [&](std::uint32_t c) {
        const std::uint32_t begin = root.start[c], end = root.start[c + 1];
        if (end - begin <= cx.leafRefs) return;
        glm::vec3 lo;
        glm::dvec3 hi;
        CellBox(root.h, c, lo, hi);
        perCell[c] = BuildChild(cx, lo, hi, root.items.data() + begin, end - begin, 1, f.eps);
      });
    } catch (const std::bad_alloc&) {
      throw RuntimeError("hgrid: out of memory for the child grids");
    }
    for (std::uint32_t c = 0; c < root.h.nCells; ++c)
      if (perCell[c]) root.SetChild(c, std::move(perCell[c]));
  }

  // Layout: every grid's cell offsets (root first), then every grid's items;
  // a child cell's items are its marker, with the child's node index, the
  // number of its references, its references, then its large references
  // (each list ascending: the SIMD tests take references in runs of a type).
  std::vector<GridBuild*> all;
  Collect(root, all);
  std::uint64_t nOffsets = 0, nItems = 0, nRefs = 0, nCells = 0, emptyCells = 0, childCells = 0;
  std::vector<std::uint64_t> offsetAt(all.size()), itemAt(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    const GridBuild& g = *all[i];
    offsetAt[i] = nOffsets;
    itemAt[i] = nItems;  // after the offsets: shifted below
    nOffsets += g.start.size() + (g.h.nCells + 3) / 4;  // the offsets, then the distance bytes
    nCells += g.h.nCells;
    for (std::uint32_t c = 0; c < g.h.nCells; ++c) {
      const std::uint32_t k = g.start[c + 1] - g.start[c];
      if (const GridBuild* child = g.ChildOf(c)) {
        ++childCells;
        nItems += 2 + child->parentLarge.size();
      } else {
        nRefs += k;
        emptyCells += k == 0;
      }
      nItems += k;
    }
  }
  for (std::uint64_t& at : itemAt) at += nOffsets;
  if (nOffsets + nItems >= std::uint64_t(CR_HGRID_CHILD))
    throw RuntimeError(fmt::format("hgrid: {} references and cell offsets do not fit 31-bit indices", nOffsets + nItems));
  HGridData out;
  try {
    out.subs.assign(std::max<std::size_t>(all.size() - 1, 1), GridHeader{});
    out.refs.resize(nOffsets + nItems);
  } catch (const std::bad_alloc&) {
    throw RuntimeError(fmt::format("hgrid: out of memory for {} references", nOffsets + nItems));
  }
  tbb::parallel_for(std::size_t(0), all.size(), [&](std::size_t i) {
    GridBuild& g = *all[i];
    g.h.first = std::uint32_t(offsetAt[i]);
    std::uint64_t at = itemAt[i];
    std::uint32_t* offsets = out.refs.data() + offsetAt[i];
    for (std::uint32_t c = 0; c < g.h.nCells; ++c) {
      offsets[c] = std::uint32_t(at);
      const GridBuild* child = g.ChildOf(c);
      if (child) {
        out.refs[at++] = CR_HGRID_CHILD | std::uint32_t(child->node - 1);
        out.refs[at++] = g.start[c + 1] - g.start[c];
      }
      for (std::uint32_t k = g.start[c]; k < g.start[c + 1]; ++k) out.refs[at++] = g.items[k];
      if (child)
        for (const std::uint32_t r : child->parentLarge) out.refs[at++] = r;
    }
    offsets[g.h.nCells] = std::uint32_t(at);
    if (skip)
      WriteDistances(g, offsets + g.h.nCells + 1);
    else
      std::fill_n(offsets + g.h.nCells + 1, (g.h.nCells + 3) / 4, 0u);
    if (i == 0)
      out.header = g.h;
    else
      out.subs[i - 1] = g.h;
  });
  out.header.nRefs = std::uint32_t(std::min<std::uint64_t>(nRefs, UINT32_MAX));

  std::function<int(const GridBuild&)> depthOf = [&](const GridBuild& g) {
    int d = 0;
    for (const auto& c : g.children) d = std::max(d, 1 + depthOf(*c));
    return d;
  };
  const int levels = 1 + depthOf(root);
  info.nodes = nCells;
  info.leaves = nCells - childCells;
  info.emptyLeaves = emptyCells;
  info.refs = nRefs;
  info.bytes = sizeof(GridHeader) * (1 + out.subs.size()) + out.refs.size() * sizeof(std::uint32_t);
  info.params = fmt::format("top={} sub={} leaf={} skip={} res={}x{}x{} grids={} levels={}", topDensity, subDensity,
                            leafRefs, skip ? "on" : "off", out.header.res[0], out.header.res[1], out.header.res[2],
                            all.size(), levels);
  return out;
}

}  // namespace cr
