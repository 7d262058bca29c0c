#include "host/trace/tracer.h"

#include "host/cl/cl_options.h"

#include <chrono>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdlib>

#include "host/cl/cl_device.h"
#include "host/cl/cl_options.h"
#include "host/core/error.h"
#include "host/reference/reference.h"
#include "host/trace/direction_scale.h"

namespace cr {

void Tracer::Trace(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits, bool occlusion, TraceStatsSum* stats)
{
  const DirectionScale scale(rays);
  TraceRays(scale.Rays(), times, hits, occlusion, stats);
  scale.Unscale(hits, occlusion);
}


void AddStats(TraceStatsSum& sum, const TraceStatsSum& s)
{
  sum.rays += s.rays;
  sum.nIT += s.nIT;
  sum.nTS += s.nTS;
  sum.nLeaves += s.nLeaves;
  sum.nEmptyLeaves += s.nEmptyLeaves;
}

Backend ParseBackend(const std::string& s)
{
  if (s == "reference") return Backend::Reference;
  if (s == "scalar") return Backend::Scalar;
  if (s == "simd") return Backend::Simd;
  if (s == "opencl") return Backend::OpenCL;
  if (s == "embree") return Backend::Embree;
  throw InputError(fmt::format("unknown backend '{}' (expected reference, scalar, simd, opencl or embree)", s));
}

const char* BackendName(Backend b)
{
  switch (b) {
    case Backend::Reference: return "reference";
    case Backend::Scalar: return "scalar";
    case Backend::Simd: return "simd";
    case Backend::OpenCL: return "opencl";
    case Backend::Embree: return "embree";
  }
  return "?";
}

Backend ResolveAutoBackend(const std::string& deviceSpec)
{
  const char* env = std::getenv("CELLRAY_DEVICE");
  const bool named = !deviceSpec.empty() || (env && *env);
  try {
    std::vector<ClDevice> devices = ListClDevices();
    if (named) return Backend::OpenCL;
    for (const ClDevice& d : devices)
      if (d.type == "gpu" && !d.simulator) return Backend::OpenCL;
    return Backend::Simd;
  } catch (const RuntimeError& e) {
    const std::string why = e.what();
    Warn(why.find("no platform found") != std::string::npos
             ? std::string("no OpenCL platform found (no driver installed, or the ICD loader finds none); using the "
                           "simd backend")
             : fmt::format("no OpenCL platform usable ({}); using the simd backend", why));
    return Backend::Simd;
  }
}

TraceConfig TracerOptions::ToConfig() const
{
  TraceConfig c;
  c.accel = ParseAccelKind(accel);
  c.backend = backend == "auto" ? ResolveAutoBackend(device) : ParseBackend(backend);
  c.fallbackToSimd = backend == "auto" && c.backend == Backend::OpenCL;
  c.precision = ParsePrecision(precision);
  c.threads = threads;
  c.params = params;
  c.isa = isa;
  c.device = device;
  c.variant = variant;
  return c;
}

bool EmbreeAvailable()
{
#ifdef CELLRAY_HAVE_EMBREE
  return true;
#else
  return false;
#endif
}

Precision ParsePrecision(const std::string& s)
{
  if (s == "fast") return Precision::Fast;
  if (s == "robust") return Precision::Robust;
  if (s == "fp64") return Precision::Fp64;
  throw InputError(fmt::format("unknown precision '{}' (expected fast, robust or fp64)", s));
}

const char* PrecisionName(Precision p)
{
  switch (p) {
    case Precision::Fast: return "fast";
    case Precision::Robust: return "robust";
    case Precision::Fp64: return "fp64";
  }
  return "?";
}

void Tracer::TracePrimary(const CameraFrame& frame, int width, int height, std::vector<HitRecord>& hits,
                          TraceStatsSum* stats)
{
  CameraFrame f = frame;
  f.width = width;
  f.height = height;
  std::vector<RayRecord> rays(std::size_t(width) * std::size_t(height));
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) rays[std::size_t(y) * std::size_t(width) + std::size_t(x)] = PrimaryRay(f, x, y);
  });
  Trace(rays, hits, false, stats);
}

namespace {

// The fp64 reference as a backend (its own BVH; the accel choice is ignored).
class ReferenceBackend final : public Tracer {
 public:
  ReferenceBackend(const Scene& scene, bool unifiedHits) : unifiedHits_(unifiedHits)
  {
    auto t0 = std::chrono::steady_clock::now();
    tracer_ = std::make_unique<ref::ReferenceTracer>(scene);
    info_.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    info_.nodes = tracer_->NodeCount();
    info_.params = "fp64 median-split bvh";
  }
  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum*) override
  {
    hits.resize(rays.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        ref::DRay ray = ref::MakeRay(rays[i]);
        if (!times.empty()) ray.time = times[i];
        ref::RefHit h = occlusion ? tracer_->IntersectP(ray) : tracer_->Intersect(ray);
        hits[i] = unifiedHits_ ? tracer_->ToUnifiedRecord(h, occlusion) : tracer_->ToRecord(h, occlusion);
      }
    });
  }
  std::string DeviceName() const override { return "cpu (fp64 reference)"; }

 private:
  std::unique_ptr<ref::ReferenceTracer> tracer_;
  bool unifiedHits_ = false;
};

}  // namespace

std::unique_ptr<Tracer> CreateScalarTracer(const Scene& scene, const TraceConfig& config);
std::unique_ptr<Tracer> CreateSimdTracer(const Scene& scene, const TraceConfig& config);
namespace simd {
AccelParams SimdTracerParams(const Scene& scene, const TraceConfig& config);
AccelParams WideLayoutParams(const Scene& scene, const TraceConfig& config);
}
std::unique_ptr<Tracer> CreateOpenCLTracer(const Scene& scene, const TraceConfig& config);
#ifdef CELLRAY_HAVE_EMBREE
std::unique_ptr<Tracer> CreateEmbreeTracer(const Scene& scene, const TraceConfig& config);
#endif

namespace {

// The first line of a message (a build failure's carries the build log).
std::string FirstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

// `--backend auto` on OpenCL: every call goes to the OpenCL tracer until one
// fails with a RuntimeError; from then on to a simd tracer, created then, and
// the failed call is repeated there (Trace and TracePrimary overwrite their
// outputs, so a half-done OpenCL call leaves nothing behind). Input errors
// are not runtime failures and pass through.
class FallbackTracer final : public Tracer {
 public:
  FallbackTracer(const Scene& scene, const TraceConfig& config) : scene_(scene), config_(config)
  {
    backend_ = Backend::OpenCL;
    try {
      primary_ = CreateOpenCLTracer(scene_, config_);
      info_ = primary_->Info();
    } catch (const RuntimeError& e) {
      FallBack(e.what());
    }
  }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    // Counters of a failed OpenCL call are not added: stats->Add happens
    // only after its last step, the read-back.
    Guard([&] { TraceInRange(Active(), rays, times, hits, occlusion, stats); });
  }
  void TracePrimary(const CameraFrame& frame, int width, int height, std::vector<HitRecord>& hits,
                    TraceStatsSum* stats) override
  {
    Guard([&] { Active().TracePrimary(frame, width, height, hits, stats); });
  }
  void Prepare(bool occlusion, bool primary) override { Guard([&] { Active().Prepare(occlusion, primary); }); }
  void Describe(nlohmann::json& j) const override
  {
    if (simd_) {
      j["fallback_from"] = "opencl";
      j["fallback_reason"] = reason_;
    }
    Current().Describe(j);
  }
  std::string DeviceName() const override { return Current().DeviceName(); }
  std::string VariantName() const override { return Current().VariantName(); }
  std::string FallbackReason() const override { return reason_; }

 private:
  Tracer& Active() { return simd_ ? *simd_ : *primary_; }
  const Tracer& Current() const { return simd_ ? *simd_ : *primary_; }

  template <typename F>
  void Guard(F&& call)
  {
    if (!simd_) {
      try {
        call();
        return;
      } catch (const RuntimeError& e) {
        FallBack(e.what());
      }
    }
    call();
  }

  void FallBack(const std::string& why)
  {
    reason_ = FirstLine(why);
    Warn(fmt::format("{}; falling back to the simd backend (--backend auto)", reason_));
    primary_.reset();
    TraceConfig c = config_;
    c.backend = Backend::Simd;
    c.fallbackToSimd = false;
    c.variant.clear();  // the OpenCL variant names mean nothing to simd: its default
    c.device.clear();
    simd_ = CreateSimdTracer(scene_, c);
    info_ = simd_->Info();
    backend_ = Backend::Simd;
  }

  const Scene& scene_;
  TraceConfig config_;
  std::unique_ptr<Tracer> primary_, simd_;
  std::string reason_;
};

std::unique_ptr<Tracer> CreateBackend(const Scene& scene, const TraceConfig& config)
{
  switch (config.backend) {
    case Backend::Reference: return std::make_unique<ReferenceBackend>(scene, config.unifiedHits);
    case Backend::Scalar: return CreateScalarTracer(scene, config);
    case Backend::Simd: return CreateSimdTracer(scene, config);
    case Backend::OpenCL: return CreateOpenCLTracer(scene, config);
    case Backend::Embree:
#ifdef CELLRAY_HAVE_EMBREE
      return CreateEmbreeTracer(scene, config);
#else
      throw InputError("backend embree: this build has no Embree (Embree 3 was not found when it was configured)");
#endif
  }
  throw RuntimeError("unknown backend");
}

}  // namespace

std::unique_ptr<Tracer> CreateTracer(const Scene& scene, const TraceConfig& config)
{
  if (config.backend == Backend::OpenCL && config.fallbackToSimd)
    return std::make_unique<FallbackTracer>(scene, config);
  std::unique_ptr<Tracer> t = CreateBackend(scene, config);
  t->backend_ = config.backend;
  return t;
}

AccelParams BackendAccelParams(const Scene& scene, const TraceConfig& config)
{
  if (config.backend == Backend::Simd) return simd::SimdTracerParams(scene, config);
  // The OpenCL backend's wide walk builds the SIMD backend's layout.
  if (config.backend == Backend::OpenCL && ClWalksWideBVH(config)) return simd::WideLayoutParams(scene, config);
  return config.params;
}

}  // namespace cr
