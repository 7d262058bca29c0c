// A tracer is a backend with its structure built and its scene uploaded. Every
// backend (reference, scalar, simd, opencl) implements the same interface, so
// trace, check, bench and render treat them alike.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/trace/stats.h"
#include "host/accel/accel.h"
#include "kernels/types.h"
#include "host/scene/camera.h"
#include "host/scene/scene.h"

namespace cr {

// The rays of a trace call, and their times (empty: every ray at time 0):
// views, so that a caller's buffer (a numpy array, a mapped file) is traced
// in place.
using RaySpan = std::span<const RayRecord>;
using TimeSpan = std::span<const float>;

// Embree: Intel's Embree 3 as a baseline (host/embree/), present only when
// the build found it (CELLRAY_HAVE_EMBREE; EmbreeAvailable()).
enum class Backend { Reference, Scalar, Simd, OpenCL, Embree };
Backend ParseBackend(const std::string& s);  // InputError on unknown names
// The backend `auto` stands for: opencl when an OpenCL GPU exists (a
// simulator such as Oclgrind does not count) or a device is named by
// `deviceSpec` / $CELLRAY_DEVICE, else simd. With no OpenCL platform
// installed at all it falls back to simd with a one-line warning. When it
// picks opencl, the caller sets TraceConfig::fallbackToSimd, so that a later
// OpenCL failure falls back too (CreateTracer).
Backend ResolveAutoBackend(const std::string& deviceSpec);
const char* BackendName(Backend b);
bool EmbreeAvailable();

enum class Precision { Fast, Robust, Fp64 };
Precision ParsePrecision(const std::string& s);
const char* PrecisionName(Precision p);

struct TraceConfig {
  Backend backend = Backend::Scalar;
  AccelKind accel = AccelKind::BVH;
  Precision precision = Precision::Robust;
  AccelParams params;
  int threads = 0;          // 0: all cores
  bool stats = false;       // gather Havran's per-ray measures
  std::string isa;          // simd: avx512 | avx2 | sse4 | scalar, empty: best available
  std::string device;       // opencl: "N" or "platform:device", empty: default
  std::string variant;      // traversal variant (e.g. ray | packet; embree: single | packet8), empty: default
  // Internal hit form for the renderer: HitRecord.prim is the unified piece
  // index g (kernels/types.h) and u, v are reported for every triangle piece.
  bool unifiedHits = false;
  // `--backend auto` chose opencl: an OpenCL runtime failure (no such device,
  // device not available, build, kernel limits, allocation, launch), at
  // creation or in any later call, switches the tracer to simd with a
  // one-line warning and repeats the call there, instead of ending the run.
  bool fallbackToSimd = false;
};

// What a user asks for by name (the CLI's options, the Python API's
// arguments): ToConfig validates the names (InputError) and resolves `auto`.
struct TracerOptions {
  std::string accel = "bvh";
  std::string backend = "auto";
  std::string precision = "robust";
  int threads = 0;
  AccelParams params;  // the builders' (CR_ACCEL_PARAMS)
  std::string isa, device, variant;
  TraceConfig ToConfig() const;
};

class Tracer {
 public:
  virtual ~Tracer() = default;
  // hits[i] answers rays[i] (closest hit, or occlusion per FORMATS.md) at
  // time times[i] in the shutter interval [0, 1] (motion blur; `times` empty:
  // every ray at time 0, as a CRRAYS01 file's rays are). stats is filled
  // only when the tracer was created with stats on. Rays whose direction is
  // too short or too long for float products reach the backend scaled by a
  // power of two, their hits' t scaled back (host/trace/direction_scale.h).
  void Trace(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits, bool occlusion, TraceStatsSum* stats);
  void Trace(RaySpan rays, std::vector<HitRecord>& hits, bool occlusion, TraceStatsSum* stats)
  {
    Trace(rays, NoTimes(), hits, occlusion, stats);
  }
  static const std::vector<float>& NoTimes()
  {
    static const std::vector<float> none;
    return none;
  }
  // Closest hits of the camera's primary rays through the pixel centres of a
  // width x height image (scene/camera.h PrimaryRay), row-major from the
  // top-left. The default generates the rays on the host and calls Trace; a
  // device backend generates them where it traces.
  virtual void TracePrimary(const CameraFrame& frame, int width, int height, std::vector<HitRecord>& hits,
                            TraceStatsSum* stats);
  // Does the one-time work a query kind needs (compiling kernels) so that
  // timed Trace (primary: TracePrimary) calls measure tracing only. They
  // do it themselves when it was not done.
  virtual void Prepare(bool occlusion, bool primary = false)
  {
    (void)occlusion;
    (void)primary;
  }
  // Backend-specific fields for the trace JSON (e.g. program_build_ms).
  virtual void Describe(nlohmann::json& j) const { (void)j; }
  virtual std::string DeviceName() const = 0;
  // What actually ran (e.g. "avx2 packet"), for the JSON output.
  virtual std::string VariantName() const { return ""; }
  const AccelInfo& Info() const { return info_; }
  // The backend that answers: the configured one, or simd once an `auto`
  // tracer has fallen back (FallbackReason then says why, in one line).
  virtual Backend ActiveBackend() const { return backend_; }
  virtual std::string FallbackReason() const { return {}; }
  // Device time of the last Trace or TracePrimary call's kernel in ms, from
  // the device's own clock (OpenCL event profiling): the wall time less the
  // transfers and the host's share. Negative for backends without one.
  virtual double LastKernelMs() const { return -1.0; }

 protected:
  // The backend's Trace, of rays whose directions are in range.
  virtual void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits, bool occlusion,
                         TraceStatsSum* stats) = 0;
  // A wrapper's call of its inner tracer, on rays its own Trace has already
  // brought in range (no second scan of the directions).
  static void TraceInRange(Tracer& inner, RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits, bool occlusion,
                           TraceStatsSum* stats)
  {
    inner.TraceRays(rays, times, hits, occlusion, stats);
  }

  AccelInfo info_;
  Backend backend_ = Backend::Scalar;  // set by CreateTracer

  friend std::unique_ptr<Tracer> CreateTracer(const Scene& scene, const TraceConfig& config);
};

std::unique_ptr<Tracer> CreateTracer(const Scene& scene, const TraceConfig& config);

// The structure's parameters a backend builds with for this scene: the
// configuration's, with the backend's own choices where they are left at 0
// (the SIMD backend's: simd/simd_tracer.cpp SimdParams). Tests that compare
// backends bit for bit build the other side with these.
AccelParams BackendAccelParams(const Scene& scene, const TraceConfig& config);

}  // namespace cr
