// The `scalar` backend: the portable kernels compiled as C++, one ray at a
// time per task, parallel over rays with oneTBB.
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "host/scalar/scalar_kernels.h"
#include "host/trace/tracer.h"

namespace cr {

namespace {

using TraceRangeFn = void (*)(const KernelArgs&, std::size_t, std::size_t, bool, TraceStatsSum*);

TraceRangeFn Pick(Precision p, bool stats)
{
  switch (p) {
    case Precision::Fast: return stats ? k_fast_stats::TraceRange : k_fast::TraceRange;
    case Precision::Fp64: return stats ? k_fp64_stats::TraceRange : k_fp64::TraceRange;
    case Precision::Robust: break;
  }
  return stats ? k_robust_stats::TraceRange : k_robust::TraceRange;
}

class ScalarTracer final : public Tracer {
 public:
  ScalarTracer(const Scene& scene, const TraceConfig& cfg)
      : scene_(scene), config_(cfg), data_(BuildAccel(scene, cfg.accel, cfg.params)), primIds_(scene.UnifiedIds()), motion_(scene.UnifiedMotion())
  {
    info_ = data_.info;
    fn_ = Pick(cfg.precision, cfg.stats);
  }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    hits.resize(rays.size());
    KernelArgs a;
    a.accel = config_.accel;
    a.data = &data_;
    a.ranges = scene_.Ranges();
#define CR_SCALAR_ARRAY_(T, U, array) a.array = scene_.array.data();
    CR_PRIM_TYPES(CR_SCALAR_ARRAY_)
#undef CR_SCALAR_ARRAY_
    a.primIds = primIds_.data();
    a.rays = rays.data();
    a.times = times.empty() ? nullptr : times.data();
    a.motion = motion_.empty() ? nullptr : motion_.data();
    a.hits = hits.data();
    a.unifiedHits = config_.unifiedHits;
    tbb::enumerable_thread_specific<TraceStatsSum> local;
    const bool wantStats = config_.stats && stats;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
      fn_(a, r.begin(), r.end(), occlusion, wantStats ? &local.local() : nullptr);
    });
    if (wantStats)
      for (const auto& s : local) AddStats(*stats, s);
  }

  std::string DeviceName() const override { return "cpu"; }
  std::string VariantName() const override { return fmt::format("{} ray", PrecisionName(config_.precision)); }

 private:
  const Scene& scene_;
  TraceConfig config_;
  AccelData data_;
  std::vector<std::uint32_t> primIds_;
  std::vector<float> motion_;  // Scene::UnifiedMotion, empty for a static scene
  TraceRangeFn fn_ = nullptr;
};

}  // namespace

std::unique_ptr<Tracer> CreateScalarTracer(const Scene& scene, const TraceConfig& config)
{
  return std::make_unique<ScalarTracer>(scene, config);
}

}  // namespace cr
