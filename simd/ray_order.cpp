#include "simd/ray_order.h"

#include <span>
#include <algorithm>
#include <cmath>
#include <cstring>

#include <tbb/parallel_for.h>

namespace cr::simd {

namespace {

double Diff(const RayRecord& a, const RayRecord& b, int axis) { return double(b.dir[axis]) - double(a.dir[axis]); }

// |(b - a) - step| relative to |step|, in directions.
double StepError(const RayRecord& a, const RayRecord& b, const double step[3], double stepLen)
{
  double e = 0.0;
  for (int k = 0; k < 3; ++k) e = std::max(e, std::fabs(Diff(a, b, k) - step[k]));
  return e / stepLen;
}

}  // namespace

int DetectImageWidth(std::span<const RayRecord> rays)
{
  const std::size_t n = rays.size();
  if (n < 16) return 0;
  // One origin (compare a sample).
  for (std::size_t i = 0; i < n; i += 1 + n / 64)
    if (std::memcmp(rays[i].org, rays[0].org, sizeof rays[0].org) != 0) return 0;
  double step[3];
  double stepLen = 0.0;
  for (int k = 0; k < 3; ++k) {
    step[k] = Diff(rays[0], rays[1], k);
    stepLen = std::max(stepLen, std::fabs(step[k]));
  }
  if (!(stepLen > 0.0)) return 0;
  constexpr double kTol = 0.25;  // row steps agree to float rounding; the wrap is a jump of many steps
  std::size_t w = 1;
  while (w < n - 1 && StepError(rays[w], rays[w + 1], step, stepLen) < kTol) ++w;
  ++w;  // rays[w - 1] -> rays[w] is the first wrap
  if (w < 2 || w >= n || n % w != 0) return 0;
  // The same wrap at the end of a few other rows, and steady steps inside them.
  const std::size_t h = n / w;
  for (std::size_t y = 1; y < h; y += 1 + h / 8) {
    const std::size_t row = y * w;
    if (StepError(rays[row], rays[row + 1], step, stepLen) >= kTol) return 0;
    if (StepError(rays[row - 1], rays[row], step, stepLen) < kTol) return 0;
  }
  return static_cast<int>(w);
}

std::vector<std::uint32_t> TileOrder(std::size_t nRays, int imageWidth, int tileW, int tileH)
{
  const std::size_t w = std::size_t(imageWidth), h = nRays / w, th = std::size_t(tileH), tw = std::size_t(tileW);
  std::vector<std::uint32_t> order(nRays);
  // Tile row r fills positions [r * th * w, ...): independent, so in parallel
  // (this runs before every packet trace of an image and would otherwise be
  // a serial part of the two-thread run).
  tbb::parallel_for(std::size_t(0), (h + th - 1) / th, [&](std::size_t r) {
    std::size_t pos = r * th * w;
    const std::size_t y0 = r * th, y1 = std::min(h, y0 + th);
    for (std::size_t tx = 0; tx < w; tx += tw)
      for (std::size_t y = y0; y < y1; ++y)
        for (std::size_t x = tx; x < std::min(w, tx + tw); ++x) order[pos++] = static_cast<std::uint32_t>(y * w + x);
  });
  return order;
}

std::vector<std::uint32_t> DirectionClassOrder(std::span<const RayRecord> rays)
{
  constexpr int kClasses = 24;
  const std::size_t n = rays.size();
  std::vector<std::uint8_t> cls(n);
  std::size_t count[kClasses + 1] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const float* d = rays[i].dir;
    const float ax = std::fabs(d[0]), ay = std::fabs(d[1]), az = std::fabs(d[2]);
    const int dom = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    const int signs = int(std::signbit(d[0])) | int(std::signbit(d[1])) << 1 | int(std::signbit(d[2])) << 2;
    cls[i] = static_cast<std::uint8_t>(3 * signs + dom);
    ++count[cls[i] + 1];
  }
  for (int c = 0; c < kClasses; ++c) count[c + 1] += count[c];
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[count[cls[i]]++] = static_cast<std::uint32_t>(i);
  return order;
}

}  // namespace cr::simd
