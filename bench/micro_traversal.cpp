// One traversal step per structure and backend: a BVH node visit, a grid
// cell (3D-DDA step), an octree node, measured as a whole trace of a ray set
// divided by the traversal steps it takes (Havran's N_TS, counted beforehand
// by a statistics run of the same configuration): items are traversal steps,
// so items/s is steps per second, intersection tests included in the cost of
// the steps that lead to them. CPU backends run on one thread here
// (tbb::global_control) so that a step's cost is a core's; OpenCL runs as
// the device schedules it. The answers are checked against the fp64
// reference before timing (0 wrong). Also: the builders.
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "host/accel/accel.h"
#include "host/cl/cl_context.h"
#include "bench/micro_common.h"
#include "host/reference/check.h"

namespace cr::micro {

namespace {

void BM_TraversalStep(benchmark::State& state, Backend backend, AccelKind accel, std::string sceneName, RayKind kind)
{
  std::unique_ptr<tbb::global_control> oneThread;
  if (backend != Backend::OpenCL)
    oneThread = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, 1);
  const Scene& scene = BenchScene(sceneName);
  const auto& rays = BenchRays(sceneName, kind);
  const bool occlusion = IsOcclusionKind(kind);
  TraceConfig cfg;
  cfg.backend = backend;
  cfg.accel = accel;
  std::unique_ptr<Tracer> tracer, statsTracer;
  try {
    tracer = CreateTracer(scene, cfg);
    cfg.stats = true;
    statsTracer = CreateTracer(scene, cfg);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  std::vector<HitRecord> hits;
  TraceStatsSum sum;
  statsTracer->Prepare(occlusion);
  statsTracer->Trace(rays, hits, occlusion, &sum);
  tracer->Prepare(occlusion);
  tracer->Trace(rays, hits, occlusion, nullptr);
  const ref::CheckResult c = ref::CheckHits(BenchReference(sceneName), rays, hits, occlusion);
  if (c.wrong != 0 || sum.nTS == 0) {
    state.SkipWithError(fmt::format("{} wrong answers (or no traversal steps counted)", c.wrong).c_str());
    return;
  }
  for (auto _ : state) {
    tracer->Trace(rays, hits, occlusion, nullptr);
    benchmark::DoNotOptimize(hits.data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(sum.nTS));
  state.counters["steps_per_ray"] = double(sum.nTS) / double(rays.size());
  state.counters["tests_per_ray"] = double(sum.nIT) / double(rays.size());
  state.counters["rays_per_s"] =
      benchmark::Counter(double(rays.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel(tracer->VariantName());
}

void BM_Build(benchmark::State& state, AccelKind accel, std::string sceneName)
{
  const Scene& scene = BenchScene(sceneName);
  AccelInfo info;
  for (auto _ : state) {
    AccelData d = BuildAccel(scene, accel, AccelParams{});
    info = d.info;
    benchmark::DoNotOptimize(d.info.refs);
  }
  if (info.refs < scene.NumUnified()) {
    state.SkipWithError("the structure references fewer primitives than the scene has");
    return;
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(scene.NumUnified()));
  state.counters["MiB"] = double(info.bytes) / (1024.0 * 1024.0);
}

bool OpenCLAvailable()
{
  try {
    (void)CreateClContext("");
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

int RegisterAll()
{
  std::vector<Backend> backends = {Backend::Scalar, Backend::Simd};
  if (OpenCLAvailable()) backends.push_back(Backend::OpenCL);
  for (const char* scene : {"flake", "mesh"})
    for (RayKind kind : {RayKind::Primary, RayKind::Diffuse})
      for (Backend b : backends)
        for (AccelKind a : kAccelKinds)
          benchmark::RegisterBenchmark(
              fmt::format("BM_TraversalStep/{}/{}/{}/{}", BackendName(b), AccelKindName(a), scene, RayKindName(kind))
                  .c_str(),
              BM_TraversalStep, b, a, std::string(scene), kind)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
  for (const char* scene : {"flake", "mesh"})
    for (AccelKind a : kAccelKinds)
      benchmark::RegisterBenchmark(fmt::format("BM_Build/{}/{}", AccelKindName(a), scene).c_str(), BM_Build, a,
                                   std::string(scene))
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
  return 0;
}

const int kRegistered = RegisterAll();

}  // namespace

}  // namespace cr::micro
