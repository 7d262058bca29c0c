// render: a scene to PNG or EXR by the Whitted or the path-tracing integrator.
#include <chrono>
#include <cstring>
#include <type_traits>
#include <array>
#include <fstream>
#include <iostream>
#include <memory>

#include <sys/resource.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/mpi/band_plan.h"
#include "host/mpi/band_tracer.h"
#include "host/mpi/mpi.h"
#include "host/render/image_io.h"
#include "host/render/renderer.h"
#include "host/scene/area_light.h"

namespace cr::cli {

namespace {

// What a distributed render reports beside the image (rank 0 prints it).
struct DistInfo {
  std::string mode;
  int ranks = 1;
  int tileRows = 0;
  std::vector<double> busyMs, wallMs;  // per rank
  std::vector<double> peakMiB;         // per rank: peak resident memory
  std::vector<std::uint64_t> bands;    // bands (tiles) rendered per rank
  // Rank 0's tiles: rows [y0, y1) and the ms it took to render them (with
  // one rank, every tile: the costs bench/mpi_simulate.py plans from).
  std::vector<std::array<double, 3>> tiles;
  std::uint64_t bytes = 0, messages = 0;
  double assembleMs = 0.0;
  std::vector<BandStats> bandStats;  // bands-data: per rank
};

// Renders this rank's part of the image (tiles handed out by a shared
// counter, or the rank's static band), and assembles the frame on rank 0:
// each rank sends its rows, rank 0 copies them into place. Other ranks get
// an empty image. Stats are summed over ranks on rank 0.
Image RenderDistributed(const Scene& scene, Tracer& tracer, BandTracer* band, RenderOptions ro, const std::string& mode,
                        int tileRows, RenderStats& stats, DistInfo& info)
{
  const int h = ro.height > 0 ? ro.height : scene.camera.height;
  const int ranks = mpi::Size(), rank = mpi::Rank();
  info.mode = mode;
  info.ranks = ranks;
  info.tileRows = mode == "tiles" ? tileRows : 0;
  std::vector<std::pair<int, int>> mine;
  // Tiles of tileRows rows, shrinking (guided) towards the end of the frame
  // when several ranks share it: a quarter of each rank's share of the rows
  // left, at least 4 rows, so that the ranks finish together without small
  // batches all along. One process (--tile-costs): tiles of tileRows rows.
  std::vector<std::pair<int, int>> tiles;
  if (mode == "tiles")
    for (int y = 0; y < h;) {
      int rows = tileRows;
      if (ranks > 1) rows = std::clamp((h - y + 4 * ranks - 1) / (4 * ranks), std::min(4, tileRows), tileRows);
      tiles.emplace_back(y, std::min(h, y + rows));
      y += rows;
    }
  mpi::WorkCounter counter(std::int64_t(tiles.size()));
  bool bandGiven = false;
  std::vector<double> tileMs;
  auto last = std::chrono::steady_clock::now();
  auto closeTile = [&]() {
    const auto now = std::chrono::steady_clock::now();
    if (tileMs.size() < mine.size()) tileMs.push_back(std::chrono::duration<double, std::milli>(now - last).count());
    last = now;
  };
  ro.nextRows = [&](int& y0, int& y1) {
    closeTile();
    if (mode == "tiles") {
      const std::int64_t t = counter.Next();
      if (t < 0) return false;
      y0 = tiles[std::size_t(t)].first;
      y1 = tiles[std::size_t(t)].second;
    } else {
      // The hypercube paper's bands: rank r holds rows [r h / N, (r + 1) h / N).
      if (bandGiven) return false;
      bandGiven = true;
      y0 = int(std::int64_t(h) * rank / ranks);
      y1 = int(std::int64_t(h) * (rank + 1) / ranks);
      if (y0 == y1) return false;
    }
    mine.emplace_back(y0, y1);
    return true;
  };
  const auto t0 = std::chrono::steady_clock::now();
  Image part = Render(scene, tracer, ro, &stats);
  closeTile();
  for (std::size_t i = 0; i < mine.size() && i < tileMs.size(); ++i)
    info.tiles.push_back({double(mine[i].first), double(mine[i].second), tileMs[i]});
  double busy = stats.totalMs;
  if (band) {
    // Serve the other bands' rays until every band is done; time spent
    // waiting in the rounds' exchanges is idle time.
    band->Finish();
    const BandStats& bs = band->Stats();
    busy = stats.totalMs + bs.serveMs - bs.exchangeMs;
    info.bandStats = mpi::GatherAll(bs);
  }
  // This rank's rows: (y0, y1) then the floats of rows [y0, y1), per band.
  std::vector<char> packed;
  const std::size_t rowFloats = std::size_t(part.width) * 3;
  for (const auto& [y0, y1] : mine) {
    const std::int32_t hdr[2] = {y0, y1};
    const char* hb = reinterpret_cast<const char*>(hdr);
    packed.insert(packed.end(), hb, hb + sizeof hdr);
    const char* fb = reinterpret_cast<const char*>(part.rgb.data() + std::size_t(y0) * rowFloats);
    packed.insert(packed.end(), fb, fb + std::size_t(y1 - y0) * rowFloats * sizeof(float));
  }
  const auto ta = std::chrono::steady_clock::now();
  const std::vector<char> all = mpi::GatherBytes(packed);
  const std::vector<RenderStats> allStats = mpi::GatherAll(stats);
  info.busyMs = mpi::GatherDouble(busy);
  {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    info.peakMiB = mpi::GatherDouble(double(ru.ru_maxrss) / 1024.0);  // Linux: KiB
  }
  info.wallMs = mpi::GatherDouble(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  std::vector<double> nb = mpi::GatherDouble(double(mine.size()));
  info.bytes = mpi::SumAll(mpi::BytesSent());
  info.messages = mpi::SumAll(mpi::MessagesSent());
  if (rank != 0) return Image{};
  for (double b : nb) info.bands.push_back(std::uint64_t(b));
  Image img;
  img.width = part.width;
  img.height = part.height;
  img.rgb.assign(part.rgb.size(), 0.0f);
  for (std::size_t at = 0; at < all.size();) {
    std::int32_t hdr[2];
    std::memcpy(hdr, all.data() + at, sizeof hdr);
    at += sizeof hdr;
    const std::size_t n = std::size_t(hdr[1] - hdr[0]) * rowFloats;
    std::memcpy(img.rgb.data() + std::size_t(hdr[0]) * rowFloats, all.data() + at, n * sizeof(float));
    at += n * sizeof(float);
  }
  // The ranks' counters summed (times: the slowest rank's).
  for (std::size_t r = 1; r < allStats.size(); ++r) AddRenderStats(stats, allStats[r]);
  info.assembleMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ta).count();
  return img;
}

}  // namespace

Run RegisterRender(CLI::App& app)
{
  struct O {
    std::string scene, out = "out.png", size, statsPath, sides = "auto", integrator = "whitted", diffuse;
    int spp = 1, depth = 0, writeEvery = 0;
    double areaLights = 0.0, timeLimit = 0.0;
    bool spd = false, fresnel = false, noProgress = false;
    std::uint64_t seed = 1;
    std::string distribute = "tiles";
    int tileRows = 64;
    bool tileCosts = false;
    std::vector<int> bandPlan;
    TracerOptions t;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "render", "Render a scene to PNG or EXR (Whitted with distributed effects, or a path tracer; docs/RENDERING.md)");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj), or gen:KIND:N (a generated scene, as in cellray bench)")->required();
  cmd->add_option("-o,--output", o->out, "Output image (.png: 8-bit sRGB, .exr: float linear)")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WxH (default: the scene's resolution)");
  cmd->add_option("--integrator", o->integrator, "whitted (point and area lights, mirrors, glass, --diffuse) or path")
      ->capture_default_str();
  cmd->add_option("--spp", o->spp,
                  "Samples per pixel (1..65536), stratified over the pixel, the lens and the area lights (not in SPD mode)")
      ->capture_default_str();
  cmd->add_option("--depth", o->depth,
                  "Maximum ray-tree depth / path vertices, the eye ray being 1 (default: 5 whitted, 8 path)");
  cmd->add_option("--diffuse", o->diffuse,
                  "Whitted: one-bounce diffuse interreflection at the first hit, cube:N (the hypercube paper's N x N "
                  "cells per cube face) or cosine:K (K cosine-distributed rays)");
  cmd->add_option("--area-lights", o->areaLights,
                  "Turn every point light into a sphere light of this radius (soft shadows; docs/RENDERING.md)");
  cmd->add_option("--write-every", o->writeEvery, "Write the image so far every N passes (one sample per pixel each)");
  cmd->add_option("--time-limit", o->timeLimit,
                  "Stop after the last pass finished within this many seconds; the image holds the passes done");
  cmd->add_flag("--spd", o->spd, "SPD procedure: 513x513 corner rays averaged to 512x512, depth 5 (../shared/SPD.md)");
  cmd->add_flag("--fresnel", o->fresnel, "Schlick Fresnel weights for reflection/refraction (not in SPD mode)");
  cmd->add_option("--sides", o->sides, "Opaque surfaces one- or two-sided: auto (two if the scene has patches), one, two")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the jitter")->capture_default_str();
  cmd->add_option("--stats", o->statsPath, "Write ray statistics (JSON) to this file");
  cmd->add_flag("--no-progress", o->noProgress, "No progress bar on stderr");
  cmd->add_option("--distribute", o->distribute,
                  "Under mpirun: tiles (dynamic tiles of --tile-rows rows, scene on every rank), bands (the "
                  "hypercube paper's static bands, one per rank) or bands-data (the paper's data-parallel bands: each "
                  "rank holds its band's primitives and passes rays on); docs/DISTRIBUTED.md")
      ->capture_default_str();
  cmd->add_option("--tile-rows", o->tileRows, "Rows per tile of --distribute tiles (1..4096); under mpirun the last tiles shrink (guided, "
                  "down to 4 rows) so that the ranks finish together")->capture_default_str();
  cmd->add_flag("--tile-costs", o->tileCosts,
                "Render tile by tile even in one process and report each tile's time in the JSON (mpi.tiles: the "
                "costs bench/mpi_simulate.py plans from)");
  cmd->add_option("--band-plan", o->bandPlan,
                  "One process: count, for each of these numbers of ranks, the rays --distribute bands-data would pass "
                  "between bands and the pieces each band would hold (JSON band_plan; bench/mpi_simulate.py)")
      ->delimiter(',');
  AddTracerOptions(cmd, o->t);
  return [o]() {
    if (o->distribute != "tiles" && o->distribute != "bands" && o->distribute != "bands-data")
      throw InputError(fmt::format("--distribute '{}': expected tiles, bands or bands-data", o->distribute));
    if (o->tileRows < 1 || o->tileRows > 4096) throw InputError(fmt::format("--tile-rows {} is not in 1..4096", o->tileRows));
    const bool distributed = mpi::Distributed();
    if (!o->bandPlan.empty() && distributed) throw InputError("--band-plan is a one-process measurement (not under mpirun)");
    for (int p : o->bandPlan)
      if (p < 1 || p > 65535) throw InputError(fmt::format("--band-plan {}: a number of ranks in 1..65535", p));
    if ((distributed || o->tileCosts) && (o->writeEvery > 0 || o->timeLimit > 0.0))
      throw InputError("--write-every and --time-limit apply to a render by one process (not under mpirun)");
    TraceConfig cfg = o->t.ToConfig();
    cfg.unifiedHits = true;
    std::unique_ptr<tbb::global_control> limit;
    if (cfg.threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, cfg.threads);
    RenderOptions ro;
    if (!o->size.empty()) ParseSize(o->size, ro.width, ro.height);
    ro.spp = o->spp;
    if (o->integrator == "whitted") ro.integrator = Integrator::Whitted;
    else if (o->integrator == "path") ro.integrator = Integrator::Path;
    else throw InputError(fmt::format("--integrator '{}': expected whitted or path", o->integrator));
    ro.maxDepth = o->depth > 0 ? o->depth : ro.integrator == Integrator::Path ? 8 : 5;
    if (o->depth < 0) throw InputError(fmt::format("--depth {} is not in 1..64", o->depth));
    if (!o->diffuse.empty()) ro.diffuse = ParseDiffuse(o->diffuse);
    ro.writeEvery = o->writeEvery;
    ro.timeLimit = o->timeLimit;
    ro.spd = o->spd;
    ro.fresnel = o->fresnel;
    ro.seed = o->seed;
    ro.progress = !o->noProgress && !distributed;
    ro.robustOffsets = cfg.backend != Backend::Embree && cfg.precision != Precision::Fast;
    if (o->sides == "auto") ro.sides = Sides::Auto;
    else if (o->sides == "one") ro.sides = Sides::One;
    else if (o->sides == "two") ro.sides = Sides::Two;
    else throw InputError(fmt::format("--sides '{}': expected auto, one or two", o->sides));
    if (ro.spd && (ro.spp != 1 || o->fresnel)) throw InputError("--spd fixes one sample per pixel corner and no Fresnel");
    if (o->areaLights < 0.0) throw InputError(fmt::format("--area-lights {}: the radius must be > 0", o->areaLights));
    if (mpi::Rank() == 0) CheckImageOutput(o->out);  // a format we write and a loadable image module, before the work
    const auto tLoad = std::chrono::steady_clock::now();
    Scene scene = LoadScene(o->scene);
    const double loadMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tLoad).count();
    if (o->areaLights > 0.0) PointLightsToSpheres(scene, o->areaLights);
    ro.onImage = [o](const Image& img, int passes) {
      WriteImage(o->out, img.width, img.height, img.rgb);
      if (!o->noProgress) std::cerr << fmt::format("cellray: {} passes: wrote {}\n", passes, o->out);
    };
    std::unique_ptr<Tracer> tracer;
    BandTracer* band = nullptr;
    if (distributed && o->distribute == "bands-data") {
      // Each rank's structure holds its band's primitives only (host/mpi/band_tracer.h).
      const int w = ro.width > 0 ? ro.width : scene.camera.width, h = ro.height > 0 ? ro.height : scene.camera.height;
      auto bt = std::make_unique<BandTracer>(scene, cfg, BandWedges::ForRows(MakeCameraFrame(scene.camera, w, h), mpi::Size()));
      band = bt.get();
      tracer = std::move(bt);
    } else {
      tracer = CreateTracer(scene, cfg);
    }
    BandPlanTracer* plan = nullptr;
    if (!o->bandPlan.empty()) {
      const int w = ro.width > 0 ? ro.width : scene.camera.width, h = ro.height > 0 ? ro.height : scene.camera.height;
      auto p = std::make_unique<BandPlanTracer>(scene, std::move(tracer), MakeCameraFrame(scene.camera, w, h), o->bandPlan);
      plan = p.get();
      tracer = std::move(p);
    }
    RenderStats stats;
    DistInfo dist;
    Image img = distributed || o->tileCosts
                    ? RenderDistributed(scene, *tracer, band, ro, o->distribute, o->tileRows, stats, dist)
                    : Render(scene, *tracer, ro, &stats);
    if (mpi::Rank() != 0) return 0;  // rank 0 writes and reports
    WriteImage(o->out, img.width, img.height, img.rgb);
    nlohmann::json j{{"scene", o->scene},
                     {"output", o->out},
                     {"backend", BackendName(tracer->ActiveBackend())},
                     {"accel", cfg.backend == Backend::Reference ? "reference-bvh" : AccelKindName(cfg.accel)},
                     {"device", tracer->DeviceName()},
                     {"width", img.width},
                     {"height", img.height},
                     {"spp", ro.spd ? 1 : ro.spp},
                     {"passes", stats.passes},
                     {"integrator", o->integrator},
                     {"diffuse", o->diffuse.empty() ? nlohmann::json(nullptr) : nlohmann::json(o->diffuse)},
                     {"area_lights", scene.areaLights.size()},
                     {"time_limited", stats.timeLimited},
                     {"spd", ro.spd},
                     {"load_ms", loadMs},
                     {"build_ms", tracer->Info().buildMs},
                     {"stats", stats}};
    if (distributed || o->tileCosts) {
      double wall = 0.0;
      for (double w : dist.wallMs) wall = std::max(wall, w);
      nlohmann::json ranks = nlohmann::json::array();
      for (int r = 0; r < dist.ranks; ++r)
        ranks.push_back({{"rank", r},
                         {"busy_ms", dist.busyMs[std::size_t(r)]},
                         {"idle_ms", wall - dist.busyMs[std::size_t(r)]},
                         {"bands", dist.bands[std::size_t(r)]},
                         {"peak_rss_mib", dist.peakMiB[std::size_t(r)]}});
      if (!dist.bandStats.empty())
        for (int r = 0; r < dist.ranks; ++r) ranks[std::size_t(r)]["bands_data"] = dist.bandStats[std::size_t(r)];
      j["mpi"] = {{"ranks", dist.ranks},         {"distribute", dist.mode},    {"tile_rows", dist.tileRows},
                  {"wall_ms", wall},             {"assemble_ms", dist.assembleMs}, {"bytes_sent", dist.bytes},
                  {"messages_sent", dist.messages}, {"per_rank", ranks}, {"tiles", dist.tiles}};
    }
    if (plan) j["band_plan"] = plan->Plans();
    if (!tracer->FallbackReason().empty()) {
      j["fallback_from"] = "opencl";
      j["fallback_reason"] = tracer->FallbackReason();
    }
    if (!o->statsPath.empty()) {
      std::string text = j.dump(2) + "\n";
      WriteFileAtomically(o->statsPath, text.data(), text.size());
    }
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
