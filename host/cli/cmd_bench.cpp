// bench: the benchmark suite (docs/BENCHMARKS.md). The main run times every
// scene x configuration x ray kind and checks each against the fp64
// reference, then renders the image-error study; --scaling and --hard run
// their own studies instead. Each writes its section of DIR/results.json
// (merged with what is there), DIR/results.md and, through bench/plot.py,
// the plots.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "host/bench/bench_options.h"
#include "host/bench/bench_row.h"
#include "host/bench/bench_scenes.h"
#include "tests/hard/gen/hard.h"
#include "host/bench/image_bench.h"
#include "host/bench/machine_info.h"
#include "host/bench/ray_bench.h"
#include "host/bench/report.h"
#include "host/bench/scaling.h"
#include "host/cl/cl_context.h"
#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr::cli {

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

template <typename T, typename Parse>
std::vector<T> ParseList(const std::vector<std::string>& items, Parse parse)
{
  std::vector<T> out;
  for (const auto& s : items) {
    T v = parse(s);
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  }
  return out;
}

// Whether an OpenCL device can be opened, and whether it has cl_khr_fp64.
void ProbeOpenCL(const std::string& device, bool& available, bool& fp64, std::string& why)
{
  try {
    ClContext c = CreateClContext(device);
    available = true;
    fp64 = c.dev.fp64;
  } catch (const std::exception& e) {
    if (!device.empty()) throw;  // a device asked for by name must exist
    available = false;
    fp64 = false;
    why = e.what();
  }
}

void PrintRow(const bench::Row& r, std::size_t index, std::size_t total, Clock::time_point t0)
{
  std::string what;
  if (!r.note.empty())
    what = r.note;
  else
    what = fmt::format("{:8.2f} Mrays/s  build {:8.1f} ms  wrong {}", r.timing.medianMs > 0.0 ? double(r.rays) / (r.timing.medianMs * 1e3) : 0.0,
                       r.structure.buildMs, r.error ? r.error->wrong : 0);
  if (r.note.empty() && r.timing.kernelMedianMs > 0.0)
    what += fmt::format("  kernel {:.2f} Mrays/s", double(r.rays) / (r.timing.kernelMedianMs * 1e3));
  fmt::print(stderr, "[{:4}/{}] {:>6.0f} s  {:<14} {:<8} {:<24} {}\n", index, total, SecondsSince(t0), r.scene,
             RayKindName(r.kind), r.combo.Label(), what);
}

json RowsJson(const std::vector<bench::Row>& rows)
{
  json a = json::array();
  for (const auto& r : rows) a.push_back(r);
  return a;
}

json OptionsJson(const bench::BenchOptions& o, int threads)
{
  std::vector<std::string> kinds;
  for (RayKind k : o.kinds) kinds.push_back(RayKindName(k));
  // The structure parameters given (CR_ACCEL_PARAMS; the others are the builders' defaults).
  json params = json::object();
#define CR_BENCH_PARAM_JSON(f, T, opt, help) \
  if (o.params.f != T{}) params[std::string(opt).substr(2)] = o.params.f;
  CR_ACCEL_PARAMS(CR_BENCH_PARAM_JSON)
#undef CR_BENCH_PARAM_JSON
  return json{{"rays", o.rays},   {"repeat", o.repeat}, {"threads", threads}, {"kinds", kinds},
              {"quick", o.quick}, {"seed", o.seed},     {"stats", o.stats},   {"structure_params", params},
              {"interleave", o.interleave}, {"interleave_max_pieces", o.interleaveMaxPieces}};
}

// Runs bench/plot.py on DIR with the first python3 that has matplotlib (the
// one on PATH may be a private interpreter without it; Debian's is
// /usr/bin/python3); a missing plotter is a note, not a failure.
void RunPlots(const std::string& root, const std::string& dir)
{
  if (root.empty()) {
    fmt::print(stderr, "bench: plots skipped: bench/plot.py not found (run it by hand: python3 bench/plot.py {})\n", dir);
    return;
  }
  for (const char* python : {"python3", "/usr/bin/python3"}) {
    const std::string probe = fmt::format("{} -c 'import matplotlib' >/dev/null 2>&1", python);
    if (std::system(probe.c_str()) != 0) continue;
    const std::string cmd = fmt::format("{} '{}/bench/plot.py' '{}' >&2", python, root, dir);
    if (std::system(cmd.c_str()) != 0) fmt::print(stderr, "bench: `{}` failed\n", cmd);
    return;
  }
  fmt::print(stderr, "bench: plots skipped: no python3 with matplotlib (python3-matplotlib)\n");
}

}  // namespace

Run RegisterBench(CLI::App& app)
{
  struct O {
    std::vector<std::string> scenes, accels, backends, kinds, precisions;
    int repeat = -1, threads = 0;
    std::uint64_t rays = 0, seed = 1;
    std::string out = "bench-out", imageScene, device;
    bool hard = false, scaling = false, quick = false, noImages = false, noPlots = false, noStats = false,
         noInterleave = false;
    std::string imageIntegrator, imageDiffuse, imageSize;
    std::vector<int> imageSpps;
    int imageReferenceSpp = 0;
    std::vector<double> sdfEps, sdfRelax;
    std::vector<long> sdfSteps;
    AccelParams params;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("bench", "Benchmark suite: structures x backends x ray kinds against Embree, with "
                                          "the error of every answer; results.json, results.md and plots");
  cmd->add_option("scenes", o->scenes,
                  "Scene files or names: SPD (balls ...), meshes (../shared/scenes/meshes/NAME.obj), "
                  "gen:" + bench::GeneratedKinds() + ":N (default: the 7 SPD scenes and the meshes)");
  cmd->add_option("--accel", o->accels, "Structures, comma-separated: " + AccelKindNames())->delimiter(',');
  cmd->add_option("--backend", o->backends, "Backends, comma-separated: reference,scalar,simd,opencl,embree")->delimiter(',');
  cmd->add_option("--kinds", o->kinds, "Ray kinds, comma-separated: primary,shadow,diffuse,random")->delimiter(',');
  cmd->add_option("--precision", o->precisions, "Precision modes, comma-separated: fast,robust,fp64")->delimiter(',');
  cmd->add_option("--repeat", o->repeat, "Timed runs per row (default 5; quick 1)")->check(CLI::Range(1, 1000));
  cmd->add_option("--rays", o->rays, "Rays per set (default 65536; quick 4096)")->check(CLI::Range(1, 1 << 26));
  cmd->add_option("--threads", o->threads, "CPU threads (0: all cores)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--device", o->device, "OpenCL device: N or platform:device (default: $CELLRAY_DEVICE, first GPU, else CPU)");
  cmd->add_option("--seed", o->seed, "Seed of the ray sets")->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--image-scene", o->imageScene, "Scene of the spp-against-error study (default: balls, else the first)");
  cmd->add_option("--sdf-eps", o->sdfEps,
                  "SDF axis: hit thresholds, comma-separated; each scene with SDF blocks runs once per value (its "
                  "rows' scene NAME@eps=E,w=W,steps=N; default: the scene's own)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--sdf-relax", o->sdfRelax, "SDF axis: relaxation factors in [1, 2), comma-separated")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 1.999999));
  cmd->add_option("--sdf-steps", o->sdfSteps, "SDF axis: step budgets (1 to 2^20), comma-separated")
      ->delimiter(',')
      ->check(CLI::Range(1l, 1l << 20));
  cmd->add_option("--image-integrator", o->imageIntegrator,
                  "Image study: whitted or path, rendered with every configuration of the run (--backend x --accel x "
                  "--precision); without it, Whitted with simd bvh robust and fast, scalar bvh fp64 and Embree");
  cmd->add_option("--image-diffuse", o->imageDiffuse,
                  "Image study: Whitted with cube:N or cosine:K diffuse gather (reference: the path tracer, 2 vertices)");
  cmd->add_option("--image-spp", o->imageSpps, "Image study: samples per pixel, comma-separated (default 1,4,16)")
      ->delimiter(',');
  cmd->add_option("--image-reference-spp", o->imageReferenceSpp, "Image study: spp of the fp64 reference (default 64)");
  cmd->add_option("--image-size", o->imageSize, "Image study: WxH (default 96x96)");
  AddAccelParamOptions(cmd, o->params);
  cmd->add_flag("--hard", o->hard, "Run the hard-case suite instead (writes DIR/HARD_CASES.md)");
  cmd->add_flag("--scaling", o->scaling, "Run the scaling study instead (generated scenes, 10^3..10^7 primitives)");
  cmd->add_flag("--quick", o->quick, "CI size: 4096 rays per set, one timed run, a tiny image study");
  cmd->add_flag("--no-images", o->noImages, "Skip the spp-against-error image study");
  cmd->add_flag("--no-plots", o->noPlots, "Do not run bench/plot.py");
  cmd->add_flag("--no-stats", o->noStats, "Skip the statistics runs (Havran's per-ray measures)");
  cmd->add_flag("--no-interleave", o->noInterleave,
                "Time each row's runs back to back (default: in rounds over all of a scene's rows, each round "
                "running every row once, for scenes up to 10^6 primitives; the scaling study always back to back)");
  return [o]() {
    const auto t0 = Clock::now();
    bench::BenchOptions b;
    b.quick = o->quick;
    b.repeat = o->repeat > 0 ? o->repeat : (o->quick ? 1 : 5);
    b.rays = o->rays > 0 ? o->rays : (o->quick ? 4096 : 65536);
    b.outDir = o->out;
    b.threads = o->threads;
    b.seed = o->seed;
    b.device = o->device;
    b.stats = !o->noStats;
    b.interleave = !o->noInterleave;
    b.images = !o->noImages;
    b.sdfEps = o->sdfEps;
    b.sdfRelax = o->sdfRelax;
    b.sdfSteps = o->sdfSteps;
    b.params = o->params;
    // Bad structure parameters are bad input for the whole run (not a
    // skipped row each): every builder checks them on an empty scene.
#define CR_BENCH_CHECK_PARAMS(N, U, l, H, Nd) BuildAccel(Scene{}, AccelKind::N, b.params);
    CR_ACCEL_TYPES(CR_BENCH_CHECK_PARAMS)
#undef CR_BENCH_CHECK_PARAMS
    b.accels = ParseList<AccelKind>(o->accels, ParseAccelKind);
    b.backends = ParseList<Backend>(o->backends, ParseBackend);
    b.precisions = ParseList<Precision>(o->precisions, ParsePrecision);
    if (!o->kinds.empty()) b.kinds = ParseList<RayKind>(o->kinds, ParseRayKind);
    if (std::find(b.backends.begin(), b.backends.end(), Backend::Embree) != b.backends.end() && !EmbreeAvailable())
      throw InputError("--backend embree: this build has no Embree (Embree 3 was not found when it was configured)");
    std::unique_ptr<tbb::global_control> limit;
    if (b.threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(b.threads));
    const int threads = b.threads > 0 ? b.threads : tbb::info::default_concurrency();
    const std::string root = bench::FindSourceRoot();
    b.commandLine = CommandLine();

    if ((o->hard || o->scaling) && !o->scenes.empty())
      throw InputError("--hard and --scaling bring their own scenes; drop the scene names");

    json results = bench::LoadResults(b.outDir);
    const double loadStart = bench::LoadAverage1();
    std::size_t nRows = 0;

    if (o->hard) {
      HardOptions h;
      h.backends = b.backends;
      h.accels = b.accels;
      h.precisions = b.precisions;
      h.quick = b.quick;
      fmt::print(stderr, "bench: hard-case suite\n");
      const auto h0 = std::chrono::steady_clock::now();
      const std::vector<HardCaseResult> hr = RunHardSuite(h);
      const double hardSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - h0).count();
      json list = json::array();
      for (const auto& r : hr)
        list.push_back(json{{"case", r.caseName},
                            {"accel", AccelKindName(r.accel)},
                            {"backend", BackendName(r.backend)},
                            {"precision", PrecisionName(r.precision)},
                            {"rays", r.rays},
                            {"wrong", r.wrong},
                            {"note", r.note}});
      const std::string md = HardTableMarkdown(hr);
      results["hard"] = json{{"command", b.commandLine}, {"machine", bench::MachineInfo(root)}, {"results", list},
                             {"markdown", md}};
      const std::string doc = HardReportMarkdown(hr, b.commandLine, hardSeconds);
      std::error_code ec;
      std::filesystem::create_directories(b.outDir, ec);
      WriteFileAtomically((std::filesystem::path(b.outDir) / "HARD_CASES.md").string(), doc.data(), doc.size());
      nRows += hr.size();
    }
    if (o->scaling) {
      const bench::BenchOptions so = bench::ScalingOptions(b);
      const auto scenes = bench::ScalingScenes(b.quick);
      // --accel and --backend narrow the study's configurations.
      std::vector<bench::Combo> combos;
      for (const auto& c : bench::ScalingCombos()) {
        const bool accelOk = b.accels.empty() || c.backend == Backend::Embree ||
                             std::find(b.accels.begin(), b.accels.end(), c.accel) != b.accels.end();
        const bool backendOk = b.backends.empty() || std::find(b.backends.begin(), b.backends.end(), c.backend) != b.backends.end();
        if (accelOk && backendOk) combos.push_back(c);
      }
      if (combos.empty()) throw InputError("--scaling: --accel/--backend leave no configuration (simd and embree run)");
      fmt::print(stderr, "bench: scaling study, {} scenes x {} configurations\n", scenes.size(), combos.size());
      const auto rows = bench::RunRayBench(so, scenes, combos, [&](const bench::Row& r, std::size_t i, std::size_t n) {
        PrintRow(r, i, n, t0);
      });
      results["scaling"] = json{{"command", b.commandLine},
                                {"machine", bench::MachineInfo(root)},
                                {"options", OptionsJson(so, threads)},
                                {"rows", RowsJson(rows)}};
      nRows += rows.size();
    }
    if (!o->hard && !o->scaling) {
      std::vector<std::string> notes;
      const auto scenes = bench::ResolveScenes(o->scenes, notes);
      for (const auto& n : notes) fmt::print(stderr, "bench: {}\n", n);
      bool clAvailable = false, clFp64 = false;
      std::string clWhy;
      const bool wantCl = b.backends.empty() ||
                          std::find(b.backends.begin(), b.backends.end(), Backend::OpenCL) != b.backends.end();
      if (wantCl) ProbeOpenCL(b.device, clAvailable, clFp64, clWhy);
      if (wantCl && !clAvailable) {
        notes.push_back(fmt::format("OpenCL rows skipped: {}", clWhy));
        fmt::print(stderr, "bench: {}\n", notes.back());
      }
      if (!EmbreeAvailable()) {
        notes.push_back("Embree rows absent: this build has no Embree");
        fmt::print(stderr, "bench: {}\n", notes.back());
      }
      const auto combos = bench::PlanCombos(b, clFp64, clAvailable);
      if (combos.empty()) throw InputError("bench: no configuration to run (check --backend/--accel/--precision)");
      fmt::print(stderr, "bench: {} scenes x {} configurations x {} ray kinds, {} rays per set, {} timed runs, {} threads\n",
                 scenes.size(), combos.size(), b.kinds.size(), b.rays, b.repeat, threads);
      const auto rows = bench::RunRayBench(
          b, scenes, combos, [&](const bench::Row& r, std::size_t i, std::size_t n) { PrintRow(r, i, n, t0); },
          [](const std::string& note) { fmt::print(stderr, "bench: {}\n", note); });
      nRows += rows.size();
      results["rows"] = RowsJson(rows);
      results.erase("images");
      if (b.images) {
        bench::ImageBenchOptions io;
        io.params = b.params;
        if (b.quick) {
          io.width = io.height = 32;
          io.spps = {1, 4};
          io.referenceSpp = 16;
        }
        io.imageDir = (std::filesystem::path(b.outDir) / "images").string();
        if (!o->imageIntegrator.empty()) {
          if (o->imageIntegrator == "path") io.integrator = Integrator::Path;
          else if (o->imageIntegrator != "whitted")
            throw InputError(fmt::format("--image-integrator '{}': expected whitted or path", o->imageIntegrator));
          io.combos = combos;
        }
        if (!o->imageDiffuse.empty()) io.diffuse = ParseDiffuse(o->imageDiffuse);
        if (!o->imageSpps.empty()) io.spps = o->imageSpps;
        if (o->imageReferenceSpp > 0) io.referenceSpp = o->imageReferenceSpp;
        if (!o->imageSize.empty()) ParseSize(o->imageSize, io.width, io.height);
        bench::SceneRef imageScene = scenes.front();
        const std::string want = o->imageScene.empty() ? "balls" : o->imageScene;
        bool found = false;
        for (const auto& s : scenes)
          if (s.name == want) {
            imageScene = s;
            found = true;
          }
        if (!found && !o->imageScene.empty()) {
          std::vector<std::string> ignored;
          imageScene = bench::ResolveScenes({o->imageScene}, ignored).front();
        }
        const auto images = bench::RunImageBench(imageScene, io, [](const std::string& line) {
          fmt::print(stderr, "bench: {}\n", line);
        });
        json a = json::array();
        for (const auto& r : images) a.push_back(r);
        results["images"] = a;
      }
      results["command"] = b.commandLine;
      results["machine"] = bench::MachineInfo(root);
      results["options"] = OptionsJson(b, threads);
      results["notes"] = notes;
      results["load_average"] = json{{"start", loadStart}, {"end", bench::LoadAverage1()}};
      results["wall_s"] = SecondsSince(t0);
    }
    results["format"] = "cellray-bench-1";
    bench::WriteResults(b.outDir, results);
    if (!o->noPlots) RunPlots(root, b.outDir);
    fmt::print(stderr, "bench: {} rows, total {:.1f} s; load average {:.2f} -> {:.2f}; results in {}/results.json, "
                       "results.md\n",
               nRows, SecondsSince(t0), loadStart, bench::LoadAverage1(), b.outDir);
    json summary{{"rows", nRows}, {"wall_s", SecondsSince(t0)}, {"out", b.outDir}};
    std::printf("%s\n", summary.dump().c_str());
    return 0;
  };
}

}  // namespace cr::cli
