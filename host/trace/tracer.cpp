#include "trace/tracer.h"

#include <chrono>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdlib>

#include "cl/cl_device.h"
#include "core/error.h"
#include "reference/reference.h"

namespace cr {

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
      if (d.type == "gpu") return Backend::OpenCL;
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
  void Trace(const std::vector<RayRecord>& rays, std::vector<HitRecord>& hits, bool occlusion, TraceStatsSum*) override
  {
    hits.resize(rays.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        ref::DRay ray = ref::MakeRay(rays[i]);
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
std::unique_ptr<Tracer> CreateOpenCLTracer(const Scene& scene, const TraceConfig& config);
#ifdef CELLRAY_HAVE_EMBREE
std::unique_ptr<Tracer> CreateEmbreeTracer(const Scene& scene, const TraceConfig& config);
#endif

std::unique_ptr<Tracer> CreateTracer(const Scene& scene, const TraceConfig& config)
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

}  // namespace cr
