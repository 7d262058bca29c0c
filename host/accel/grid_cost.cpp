// The uniform grid's resolution by a cost model (--grid-density 0, the
// default): instead of a fixed lambda * N cells, the resolution of the lambda
// in kCandidates whose estimated cost per ray is lowest. The estimate walks
// sample rays (the scene's camera rays and as many random lines through the
// box, standing in for secondary rays) through a model of each candidate
// grid: per cell its references (primitive bounding boxes over cells, each
// grown by the grid's epsilon) and its coverage, the chance that a line
// through the cell meets a surface there (Crofton: a convex body of surface
// area S inside a convex cell of area A is met by that fraction S / A of the
// lines through the cell; a primitive's surface is taken as half its box's,
// shared evenly by the cells its box meets). A ray pays a step per cell and
// kTestCost per reference while it survives, and survives a cell with
// probability 1 - coverage: the surface area heuristic of a grid with the
// rays' termination, which is what separates a sparse grid (few steps, many
// tests) from a dense one.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "host/accel/grid_build.h"
#include "host/scene/camera.h"

namespace cr::gridbuild {

namespace {

// A primitive test against a cell step (SIMD backend, robust mode: a
// triangle or sphere test costs about two 3D-DDA steps).
constexpr double kTestCost = 2.0;
constexpr double kCandidates[] = {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0};
// Camera rays on a kSampleSide^2 lattice, and as many random lines.
constexpr int kSampleSide = 32;
// Model cells at most (8 bytes each: references and coverage).
constexpr std::uint64_t kMaxModelCells = std::uint64_t(1) << 26;
// At most this many primitives are modelled; beyond, every k-th, with its
// counts and coverage weighted by k.
constexpr std::uint32_t kMaxModelPrims = std::uint32_t(1) << 18;
// A ray whose survival falls below this has ended.
constexpr double kDead = 1e-3;

struct Line {
  glm::dvec3 o, d;
};

std::vector<Line> SampleLines(const Scene& scene, const Frame& f)
{
  std::vector<Line> lines;
  const CameraFrame cam = MakeCameraFrame(scene.camera, kSampleSide, kSampleSide);
  for (int y = 0; y < kSampleSide; ++y)
    for (int x = 0; x < kSampleSide; ++x) {
      const RayRecord r = PrimaryRay(cam, x, y);
      lines.push_back({glm::dvec3(r.org[0], r.org[1], r.org[2]), glm::dvec3(r.dir[0], r.dir[1], r.dir[2])});
    }
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const glm::dvec3 lo(f.lo), ext = f.hi - lo;
  for (int i = 0; i < kSampleSide * kSampleSide; ++i) {
    const glm::dvec3 o = lo + ext * glm::dvec3(u(rng), u(rng), u(rng));
    const double z = 2.0 * u(rng) - 1.0, phi = 6.283185307179586 * u(rng), s = std::sqrt(1.0 - z * z);
    lines.push_back({o, glm::dvec3(s * std::cos(phi), s * std::sin(phi), z)});
  }
  return lines;
}

// The expected cost per line of the grid h with per-cell references and
// coverage.
double WalkCost(const GridHeader& h, const std::vector<float>& refs, const std::vector<float>& cover,
                const std::vector<Line>& lines)
{
  return tbb::parallel_reduce(
             tbb::blocked_range<std::size_t>(0, lines.size()), 0.0,
             [&](const tbb::blocked_range<std::size_t>& rg, double sum) {
               for (std::size_t i = rg.begin(); i != rg.end(); ++i) {
                 const Line& l = lines[i];
                 double t0 = 0.0, t1 = INFINITY;
                 for (int a = 0; a < 3; ++a) {
                   const double inv = 1.0 / l.d[a];
                   double ta = (double(h.bmin[a]) - l.o[a]) * inv, tb = (double(h.bmax[a]) - l.o[a]) * inv;
                   if (std::isnan(ta) || std::isnan(tb)) continue;
                   if (ta > tb) std::swap(ta, tb);
                   t0 = std::max(t0, ta);
                   t1 = std::min(t1, tb);
                 }
                 if (!(t0 <= t1)) continue;
                 int c[3], step[3];
                 double tNext[3], tDelta[3];
                 for (int a = 0; a < 3; ++a) {
                   const double cs = double(h.cellSize[a]);
                   const double p = l.o[a] + t0 * l.d[a];
                   c[a] = std::clamp(int(std::floor((p - double(h.bmin[a])) / cs)), 0, int(h.res[a]) - 1);
                   step[a] = l.d[a] < 0.0 ? -1 : 1;
                   const double plane = double(h.bmin[a]) + cs * (c[a] + (step[a] > 0 ? 1 : 0));
                   tNext[a] = l.d[a] == 0.0 ? INFINITY : (plane - l.o[a]) / l.d[a];
                   tDelta[a] = l.d[a] == 0.0 ? INFINITY : cs / std::fabs(l.d[a]);
                 }
                 double survive = 1.0;
                 for (;;) {
                   const std::size_t idx = std::size_t(c[0]) + h.res[0] * (std::size_t(c[1]) + h.res[1] * std::size_t(c[2]));
                   sum += survive * (1.0 + kTestCost * double(refs[idx]));
                   survive *= 1.0 - std::min(1.0, double(cover[idx]));
                   if (survive < kDead) break;
                   const int a = tNext[0] < tNext[1] ? (tNext[0] < tNext[2] ? 0 : 2) : (tNext[1] < tNext[2] ? 1 : 2);
                   if (tNext[a] > t1) break;
                   c[a] += step[a];
                   if (c[a] < 0 || c[a] >= int(h.res[a])) break;
                   tNext[a] += tDelta[a];
                 }
               }
               return sum;
             },
             std::plus<double>()) /
         double(lines.size());
}

}  // namespace

Res ChooseResolutionByCost(const Scene& scene, const Frame& f, const std::vector<Bounds>& boxes, double& density,
                           std::vector<std::pair<double, double>>* costs)
{
  const std::uint32_t n = std::uint32_t(boxes.size());
  const std::uint32_t stride = std::max<std::uint32_t>(1, (n + kMaxModelPrims - 1) / kMaxModelPrims);
  const std::vector<Line> lines = SampleLines(scene, f);
  Res best;
  double bestCost = INFINITY;
  density = kCandidates[0];
  int rising = 0;
  for (double lambda : kCandidates) {
    Res res = ChooseResolution(f.ext, lambda * double(n));
    CapResolution(res, f.lo, f.hi, f.scale);
    if (res.Cells() > kMaxModelCells) break;
    const GridHeader h = MakeHeader(f.lo, f.hi, res);
    std::vector<float> refs(h.nCells, 0.0f), cover(h.nCells, 0.0f);
    const double cellArea = 2.0 * (double(h.cellSize[0]) * h.cellSize[1] + double(h.cellSize[1]) * h.cellSize[2] +
                                   double(h.cellSize[2]) * h.cellSize[0]);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, (n + stride - 1) / stride),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                        for (std::uint32_t s = r.begin(); s != r.end(); ++s) {
                          const Bounds& b = boxes[std::size_t(s) * stride];
                          int first[3], last[3];
                          for (int a = 0; a < 3; ++a) CellRange(h, a, b.lo[a], b.hi[a], f.eps, first[a], last[a]);
                          const glm::dvec3 e = glm::dvec3(b.hi) - glm::dvec3(b.lo);
                          const double k = double(last[0] - first[0] + 1) * double(last[1] - first[1] + 1) *
                                           double(last[2] - first[2] + 1);
                          const float share = float(stride * (e.x * e.y + e.y * e.z + e.z * e.x) / (k * cellArea));
                          for (int z = first[2]; z <= last[2]; ++z)
                            for (int y = first[1]; y <= last[1]; ++y)
                              for (int x = first[0]; x <= last[0]; ++x) {
                                const std::size_t idx = std::size_t(x) + h.res[0] * (std::size_t(y) + h.res[1] * std::size_t(z));
                                std::atomic_ref<float>(refs[idx]).fetch_add(float(stride), std::memory_order_relaxed);
                                std::atomic_ref<float>(cover[idx]).fetch_add(share, std::memory_order_relaxed);
                              }
                        }
                      });
    const double cost = WalkCost(h, refs, cover, lines);
    if (costs) costs->emplace_back(lambda, cost);
    if (cost < bestCost) {
      bestCost = cost;
      best = res;
      density = lambda;
      rising = 0;
    } else if (++rising == 2) {
      break;  // past the minimum
    }
  }
  if (!std::isfinite(bestCost)) {
    // Not one candidate fits the model's memory (over 10^8 primitives): the
    // fixed density of old.
    density = kDefaultDensity;
    best = ChooseResolution(f.ext, density * double(n));
    CapResolution(best, f.lo, f.hi, f.scale);
  }
  return best;
}

}  // namespace cr::gridbuild
