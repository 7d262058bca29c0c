#include "host/render/progress.h"

#include <cstdio>

#include <unistd.h>

namespace cr {

Progress::Progress(std::uint64_t total, bool enabled)
    : total_(total), enabled_(enabled && ::isatty(2)), start_(std::chrono::steady_clock::now()), last_(start_)
{
}

void Progress::Update(std::uint64_t done, std::uint64_t rays, bool force)
{
  if (!enabled_) return;
  auto now = std::chrono::steady_clock::now();
  double elapsed = std::chrono::duration<double>(now - start_).count();
  if (!force && (elapsed < 1.0 || std::chrono::duration<double>(now - last_).count() < 0.25)) return;
  last_ = now;
  shown_ = true;
  const double frac = total_ ? double(done) / double(total_) : 1.0;
  const int width = 30, filled = int(frac * width + 0.5);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
  bar[width] = 0;
  std::fprintf(stderr, "\r[%s] %5.1f%%  %.2f Mrays/s  %.1f s", bar, 100.0 * frac, double(rays) / elapsed * 1e-6, elapsed);
  std::fflush(stderr);
}

void Progress::Finish(std::uint64_t rays)
{
  if (!shown_) return;
  Update(total_, rays, true);
  std::fprintf(stderr, "\n");
}

}  // namespace cr
