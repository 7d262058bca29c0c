// What the integrators of host/render/ share (internal to the renderer):
// the camera samples of a pass, stratified random numbers, and shadow rays
// towards a point sampled on an area light.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "host/render/renderer.h"
#include "host/scene/camera.h"
#include "host/scene/surface.h"

namespace cr {

struct RenderContext {
  const Scene& scene;
  const RenderOptions& opt;  // normalised by Render (spd, depth)
  CameraFrame frame;
  int cw = 0, ch = 0;  // sample points per row and column (SPD: the corners)
  int sx = 1, sy = 1;  // strata of a pixel's spp samples
  bool twoSidedOpaque = false;
  float intensity = 1.0f;      // the SPD's point-light intensity
  float pointIntensity = 1.0f;  // a point light's radiant intensity per unit colour (path)

  // Sample k of point `point`: its index in the seeded sequences.
  std::uint64_t Sample(std::uint64_t point, int k) const { return point * std::uint64_t(opt.spp) + std::uint64_t(k); }
  double Random(std::uint64_t sample, std::uint64_t stream) const;
  // A point of [0, 1)^2 in stratum k of the pixel's sx x sy strata, the
  // strata of each point and stream visited in their own hashed order.
  glm::dvec2 Stratified(std::uint64_t point, int k, std::uint64_t stream) const;
  // The camera ray of sample k at point `point` (pixel jitter, lens).
  RayRecord CameraRay(std::uint64_t point, int k) const;
  // The time in the shutter interval [0, 1) of sample k at point `point`
  // (motion blur), stratified over the pixel's samples; every ray of the
  // sample's path has it. 0 for a static scene.
  float Time(std::uint64_t point, int k) const;
  // The times of a queue's rays (elements with a chunk-relative `point`) of
  // sample k in the chunk that starts at `begin`; left empty for a static
  // scene (Tracer::Trace: every ray at time 0).
  template <class Q>
  void Times(const std::vector<Q>& queue, std::uint64_t begin, int k, std::vector<float>& times) const
  {
    times.clear();
    if (!scene.hasMotion) return;
    times.resize(queue.size());
    for (std::size_t i = 0; i < queue.size(); ++i) times[i] = Time(begin + queue[i].point, k);
  }
};

// A ray of one pass's chunk [begin, end) of points: each integrator traces
// sample k of every point and adds what it carries back into
// out[point - begin].
void WhittedChunk(const RenderContext& ctx, Tracer& tracer, std::uint64_t begin, std::uint64_t end, int k,
                  glm::vec3* out, RenderStats& st, std::uint64_t& rays);
void PathChunk(const RenderContext& ctx, Tracer& tracer, std::uint64_t begin, std::uint64_t end, int k, glm::vec3* out,
               RenderStats& st, std::uint64_t& rays);

// A shadow ray and the light it delivers to out[point] if unblocked.
struct ShadowRay {
  RayRecord ray;
  glm::vec3 light{0.0f};
  std::uint32_t point = 0;
  std::uint32_t sourcePrim = 0;
  std::uint8_t sourceOpaque = 0;  // only opaque surfaces can be self-shadowed in error
  std::uint8_t valid = 0;
};

inline double MsSince(std::chrono::steady_clock::time_point a)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
}

// Traces the rays of a queue (elements with a `ray` and a `point`) of
// sample k in the chunk that starts at `begin` as one closest-hit batch, at
// their samples' times.
template <class Q>
void TraceQueue(const RenderContext& ctx, std::uint64_t begin, int k, Tracer& tracer, const std::vector<Q>& queue,
                std::vector<RayRecord>& batch, std::vector<HitRecord>& hits, RenderStats& st, std::uint64_t& raysCast)
{
  batch.resize(queue.size());
  for (std::size_t i = 0; i < queue.size(); ++i) batch[i] = queue[i].ray;
  std::vector<float> times;
  ctx.Times(queue, begin, k, times);
  const auto t0 = std::chrono::steady_clock::now();
  tracer.Trace(batch, times, hits, false, nullptr);
  st.traceMs += MsSince(t0);
  raysCast += queue.size();
}

// Compacts the valid shadow rays, traces them as one any-hit batch (at
// their samples' times: sample k of the chunk that starts at `begin`), and
// adds the light of the unblocked ones to out[point] (counting blocked ones,
// and those blocked by their own opaque primitive).
void TraceShadows(const RenderContext& ctx, std::uint64_t begin, int k, Tracer& tracer, std::vector<ShadowRay>& shadows, glm::vec3* out,
                  std::vector<RayRecord>& batch, std::vector<HitRecord>& hits, RenderStats& st,
                  std::uint64_t& raysCast);

}  // namespace cr
