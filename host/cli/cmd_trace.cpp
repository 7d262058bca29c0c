// rays, trace and check.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "host/cli/commands.h"
#include "host/prims/sdf_steps.h"
#include "host/core/error.h"
#include "host/mpi/mpi.h"
#include "host/io/rays_io.h"
#include "host/rays/raygen.h"
#include "host/reference/check.h"
#include "host/reference/reference.h"
#include "host/scene/camera.h"

namespace cr::cli {

namespace {

std::unique_ptr<tbb::global_control> LimitThreads(int threads)
{
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
}

void CheckCount(const std::string& raysPath, std::size_t rays, const std::string& hitsPath, std::size_t hits)
{
  if (rays != hits)
    throw InputError(hitsPath, 0, fmt::format("{} hits for {} rays in {}", hits, rays, raysPath));
}

}  // namespace

Run RegisterRays(CLI::App& app)
{
  struct O {
    std::string scene, kind = "primary", size, out;
    bool spd = false;
    std::uint64_t seed = 1, count = 0;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("rays", "Generate a ray set (.rays) for a scene");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj), or gen:KIND:N (a generated scene, as in cellray bench)")->required();
  cmd->add_option("--kind", o->kind, "primary, shadow, diffuse or random")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WxH for primary samples (default: the scene's resolution)");
  cmd->add_flag("--spd-corners", o->spd, "Primary rays through the (W+1)x(H+1) pixel corners (SPD procedure)");
  cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str();
  cmd->add_option("--count", o->count, "Secondary or random rays to produce (default: W*H)");
  cmd->add_option("--threads", o->threads, "CPU threads (0: all cores)");
  cmd->add_option("-o,--output", o->out, "Output .rays file")->required();
  return [o]() {
    auto limit = LimitThreads(o->threads);
    RayGenOptions g;
    g.kind = ParseRayKind(o->kind);
    if (!o->size.empty()) ParseSize(o->size, g.width, g.height);
    g.spdCorners = o->spd;
    g.seed = o->seed;
    g.count = o->count;
    if (g.spdCorners && g.kind != RayKind::Primary) throw InputError("--spd-corners applies to --kind primary only");
    Scene scene = LoadScene(o->scene);
    ref::ReferenceTracer tracer(scene);
    std::vector<float> times;  // a scene with motion: CRRAYS02, a time per ray
    std::vector<RayRecord> rays = GenerateRays(scene, tracer, g, &times);
    WriteRays(o->out, rays, times);
    nlohmann::json j{{"scene", o->scene}, {"kind", o->kind},           {"rays", rays.size()},
                     {"output", o->out},  {"timed", !times.empty()}};
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

Run RegisterTrace(CLI::App& app)
{
  struct O {
    std::string scene, rays, out, primary;
    bool occlusion = false, stats = false;
    int repeat = 1;
    TracerOptions t;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("trace", "Trace a ray set; print one JSON line; optionally write .hits");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj), or gen:KIND:N (a generated scene, as in cellray bench)")->required();
  auto* raysOpt = cmd->add_option("--rays", o->rays, "Input .rays file");
  cmd->add_option("--primary", o->primary,
                  "Trace the camera's primary rays of a WxH image instead of a .rays file (generated on the device "
                  "by backends that can)")
      ->excludes(raysOpt);
  cmd->add_flag("--occlusion", o->occlusion, "Any-hit (shadow) query instead of closest hit");
  cmd->add_option("--repeat", o->repeat, "Timed repetitions; trace_ms is their median")->check(CLI::Range(1, 1000));
  cmd->add_flag("--stats", o->stats, "Add Havran's per-ray and per-structure measures");
  cmd->add_option("-o,--output", o->out, "Output .hits file");
  AddTracerOptions(cmd, o->t);
  return [o]() {
    TraceConfig cfg = o->t.ToConfig();
    cfg.stats = o->stats;
    auto limit = LimitThreads(cfg.threads);
    if (o->rays.empty() && o->primary.empty()) throw InputError("trace: give --rays FILE or --primary WxH");
    if (!o->primary.empty() && o->occlusion) throw InputError("--primary traces closest hits; drop --occlusion");
    Scene scene = LoadScene(o->scene);
    int width = 0, height = 0;
    std::vector<RayRecord> rays;
    std::vector<float> rayTimes;  // CRRAYS02: one per ray
    if (o->primary.empty())
      rays = ReadRays(o->rays, &rayTimes);
    else
      ParseSize(o->primary, width, height);
    // Under mpirun: this rank traces its contiguous slice of the rays; rank
    // 0 gathers the hits in input order.
    const bool distributed = mpi::Distributed();
    if (distributed && !o->primary.empty()) throw InputError("trace under mpirun: give --rays (not --primary)");
    if (distributed && o->stats) throw InputError("trace under mpirun: --stats counts one process's rays; drop it");
    const std::size_t nAll = rays.size();
    if (distributed) {
      const std::size_t b = nAll * std::size_t(mpi::Rank()) / std::size_t(mpi::Size());
      const std::size_t e = nAll * std::size_t(mpi::Rank() + 1) / std::size_t(mpi::Size());
      rays = std::vector<RayRecord>(rays.begin() + std::ptrdiff_t(b), rays.begin() + std::ptrdiff_t(e));
      if (!rayTimes.empty())
        rayTimes = std::vector<float>(rayTimes.begin() + std::ptrdiff_t(b), rayTimes.begin() + std::ptrdiff_t(e));
    }
    const std::size_t nRays = o->primary.empty() ? rays.size() : std::size_t(width) * std::size_t(height);
    const CameraFrame frame = MakeCameraFrame(scene.camera, width, height);
    auto tracer = CreateTracer(scene, cfg);
    tracer->Prepare(o->occlusion, !o->primary.empty());
    std::vector<HitRecord> hits;
    std::vector<double> times, kernelTimes;
    TraceStatsSum stats;
    for (int r = 0; r < o->repeat; ++r) {
      TraceStatsSum* sp = (r == 0 && o->stats) ? &stats : nullptr;
      auto t0 = std::chrono::steady_clock::now();
      if (o->primary.empty())
        tracer->Trace(rays, rayTimes, hits, o->occlusion, sp);
      else
        tracer->TracePrimary(frame, width, height, hits, sp);
      times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (tracer->LastKernelMs() >= 0.0) kernelTimes.push_back(tracer->LastKernelMs());
    }
    std::sort(times.begin(), times.end());
    double median = times[times.size() / 2];
    nlohmann::json mpiInfo;
    if (distributed) {
      std::vector<char> mine(hits.size() * sizeof(HitRecord));
      if (!hits.empty()) std::memcpy(mine.data(), hits.data(), mine.size());
      const std::vector<char> all = mpi::GatherBytes(mine);
      const std::vector<double> medians = mpi::GatherDouble(median);
      const std::uint64_t bytes = mpi::SumAll(mpi::BytesSent()), messages = mpi::SumAll(mpi::MessagesSent());
      if (mpi::Rank() != 0) return 0;  // rank 0 writes and reports
      hits.resize(nAll);
      if (nAll) std::memcpy(hits.data(), all.data(), nAll * sizeof(HitRecord));
      median = *std::max_element(medians.begin(), medians.end());  // the slowest rank's
      mpiInfo = {{"ranks", mpi::Size()}, {"trace_ms_per_rank", medians}, {"bytes_sent", bytes},
                 {"messages_sent", messages}};
    }
    const std::size_t nReported = distributed ? nAll : nRays;
    if (!o->out.empty()) WriteHits(o->out, hits);
    nlohmann::json j;
    j["scene"] = o->scene;
    if (!o->primary.empty()) j["primary"] = o->primary;
    j["accel"] = cfg.backend == Backend::Reference ? "reference-bvh" : AccelKindName(cfg.accel);
    j["backend"] = BackendName(tracer->ActiveBackend());
    j["precision"] = PrecisionName(cfg.precision);
    j["variant"] = tracer->VariantName();
    j["device"] = tracer->DeviceName();
    j["threads"] = cfg.threads > 0 ? cfg.threads : tbb::info::default_concurrency();
    j["query"] = o->occlusion ? "occlusion" : "closest";
    j["rays"] = nReported;
    j["build_ms"] = tracer->Info().buildMs;
    j["trace_ms"] = median;
    j["trace_ms_min"] = times.front();
    j["trace_ms_max"] = times.back();
    j["repeat"] = o->repeat;
    j["mrays_per_s"] = median > 0.0 ? double(nReported) / (median * 1e3) : 0.0;
    if (distributed) j["mpi"] = mpiInfo;
    // The kernel's device time alone (OpenCL): the figure that compares
    // structures on a device whose transfers dominate the wall time.
    if (!distributed && kernelTimes.size() == times.size()) {
      std::sort(kernelTimes.begin(), kernelTimes.end());
      const double km = kernelTimes[kernelTimes.size() / 2];
      j["kernel_ms"] = km;
      j["kernel_mrays_per_s"] = km > 0.0 ? double(nRays) / (km * 1e3) : 0.0;
    }
    std::uint64_t nHit = 0;
    for (const auto& h : hits) nHit += h.prim != CR_NO_HIT;
    j["hits"] = nHit;
    tracer->Describe(j);
    if (o->stats) {
      const double n = nRays == 0 ? 1.0 : double(nRays);
      j["per_ray"] = {{"intersection_tests", double(stats.nIT) / n},
                      {"traversal_steps", double(stats.nTS) / n},
                      {"leaves_visited", double(stats.nLeaves) / n},
                      {"empty_leaves_visited", double(stats.nEmptyLeaves) / n}};
      j["structure"] = tracer->Info();
      if (!scene.sdfs.empty()) {
        // SDF blocks: their marches replayed on the host (the kernels
        // count no march steps).
        std::vector<RayRecord> traced = rays;
        if (!o->primary.empty()) {
          CameraFrame f = frame;
          f.width = width;
          f.height = height;
          traced.resize(nRays);
          for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) traced[std::size_t(y) * std::size_t(width) + std::size_t(x)] = PrimaryRay(f, x, y);
        }
        const SdfMarchCount m =
            CountSdfMarches(scene, traced, hits, o->occlusion, cfg.precision == Precision::Fast);
        j["sdf"] = {{"marches_per_ray", double(m.marches) / n},
                    {"steps_per_ray", double(m.evals) / n},
                    {"steps_per_march", m.marches ? double(m.evals) / double(m.marches) : 0.0}};
      }
    }
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

Run RegisterCheck(CLI::App& app)
{
  struct O {
    std::string scene, rays, hits;
    bool occlusion = false;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("check", "Compare a .hits file with the fp64 reference; print JSON");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj), or gen:KIND:N (a generated scene, as in cellray bench)")->required();
  cmd->add_option("--rays", o->rays, "The .rays file that was traced")->required();
  cmd->add_option("--hits", o->hits, "The .hits file to check")->required();
  cmd->add_flag("--occlusion", o->occlusion, "The hits answer the any-hit (shadow) query");
  cmd->add_option("--threads", o->threads, "CPU threads (0: all cores)");
  return [o]() {
    auto limit = LimitThreads(o->threads);
    Scene scene = LoadScene(o->scene);
    std::vector<float> rayTimes;
    std::vector<RayRecord> rays = ReadRays(o->rays, &rayTimes);
    std::vector<HitRecord> hits = ReadHits(o->hits);
    CheckCount(o->rays, rays.size(), o->hits, hits.size());
    ref::ReferenceTracer tracer(scene);
    ref::CheckResult r = ref::CheckHits(tracer, rays, hits, o->occlusion, rayTimes);
    nlohmann::json j{{"scene", o->scene},
                     {"query", o->occlusion ? "occlusion" : "closest"},
                     {"rays", r.rays},
                     {"agree", r.agree},
                     {"ties", r.ties},
                     {"flips", r.flips},
                     {"wrong", r.wrong},
                     {"wrong_missed", r.wrongMissed},
                     {"wrong_farther", r.wrongFarther},
                     {"wrong_not_on_prim", r.wrongNotOnPrim},
                     {"max_rel_t_err", r.maxRelTErr},
                     {"mean_rel_t_err", r.meanRelTErr},
                     {"tolerance", "delta(t) = 2^-16 (|o|inf + t |d|inf) (docs/TOLERANCE.md)"},
                     {"first_wrong", r.firstWrong},
                     {"first_wrong_why", r.firstWrongWhy}};
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
