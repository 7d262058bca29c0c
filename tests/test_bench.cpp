// `cellray bench`: the CI-sized run through the real binary (files written,
// Embree rows present when Embree is, 0 wrong in every robust row), the
// planning of configurations, the comparison table, and bad input.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/bench/bench_options.h"
#include "host/bench/report.h"
#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;

namespace {

fs::path TempDir(const std::string& name)
{
  const fs::path d = test::ProcessTempDir("cellray_bench") / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

int RunBinary(const std::string& args, const fs::path& dir, std::string* err = nullptr)
{
  const fs::path errPath = dir / "stderr.txt";
  const std::string cmd =
      fmt::format("{} {} >{} 2>{}", CELLRAY_BINARY, args, (dir / "stdout.txt").string(), errPath.string());
  const int status = std::system(cmd.c_str());
  if (err) {
    std::ifstream in(errPath);
    std::stringstream ss;
    ss << in.rdbuf();
    *err = ss.str();
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool HaveMatplotlib()
{
  return std::system("python3 -c 'import matplotlib' >/dev/null 2>&1") == 0 ||
         std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
}

}  // namespace

TEST_CASE("bench --quick on one scene: files, Embree rows, 0 wrong in robust rows")
{
  const fs::path dir = TempDir("quick");
  const fs::path out = dir / "out";
  // OpenCL is left out: a cold program cache would make this test slow; the
  // OpenCL backends have their own conformance tests.
  const std::string backends = EmbreeAvailable() ? "simd,scalar,embree" : "simd,scalar";
  std::string err;
  const int code = RunBinary(fmt::format("bench --quick {} --backend {} --out {}", test::SpdPath("tetra"), backends,
                                         out.string()),
                             dir, &err);
  INFO("stderr: ", err);
  REQUIRE(code == 0);
  REQUIRE(fs::is_regular_file(out / "results.json"));
  REQUIRE(fs::is_regular_file(out / "results.md"));
  CHECK(fs::is_regular_file(out / "rays" / "tetra-primary-4096-s1.rays"));
  if (HaveMatplotlib()) {
    CHECK(fs::is_regular_file(out / "plots" / "speed_vs_error.png"));
    CHECK(fs::is_regular_file(out / "plots" / "speed_bars.svg"));
  } else {
    MESSAGE("SKIPPED: plots (no python3 with matplotlib)");
  }

  std::ifstream f(out / "results.json");
  const nlohmann::json res = nlohmann::json::parse(f);
  REQUIRE(res["rows"].is_array());
  CHECK(res["machine"]["cpu_model"].is_string());
  CHECK(res["command"].get<std::string>().find("bench --quick") != std::string::npos);
  std::set<std::string> embreeLabels;
  int robustRows = 0;
  for (const auto& r : res["rows"]) {
    INFO(r.dump());
    CHECK(r["scene"] == "tetra");
    CHECK(r["rays"].get<std::uint64_t>() > 0);
    REQUIRE(r["error"].is_object());
    REQUIRE(r["mrays_per_s"].is_object());
    CHECK(r["mrays_per_s"]["median"].get<double>() > 0.0);
    if (r["backend"] == "embree") embreeLabels.insert(r["label"].get<std::string>() + "/" + r["kind"].get<std::string>());
    if (r["precision"] == "robust") {
      ++robustRows;
      CHECK(r["error"]["wrong"] == 0);
      CHECK(r["per_ray"].is_object());  // statistics run of our backends
    }
  }
  // (simd and scalar x every structure, and the SIMD BVH's named walks,
  // single and packet) x 4 kinds
  CHECK(robustRows == (2 * int(std::size(kAccelKinds)) + 2) * 4);
  if (EmbreeAvailable()) {
    for (const char* kind : {"primary", "shadow", "diffuse", "random"}) {
      CHECK(embreeLabels.count(std::string("embree single/") + kind) == 1);
      CHECK(embreeLabels.count(std::string("embree packet8/") + kind) == 1);
    }
  } else {
    MESSAGE("SKIPPED: Embree rows (this build has no Embree)");
  }
  REQUIRE(res["images"].is_array());
  CHECK(!res["images"].empty());
  std::ifstream md(out / "results.md");
  std::stringstream ss;
  ss << md.rdbuf();
  CHECK(ss.str().find("| tetra | primary |") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("bench: unknown scenes, backends and bad structure parameters are bad input")
{
  const fs::path dir = TempDir("bad");
  std::string err;
  CHECK(RunBinary("bench no_such_scene --out " + (dir / "o").string(), dir, &err) == 2);
  CHECK(err.find("unknown scene 'no_such_scene'") != std::string::npos);
  CHECK(RunBinary("bench tetra --backend cuda --out " + (dir / "o").string(), dir, &err) == 2);
  CHECK(err.find("unknown backend 'cuda'") != std::string::npos);
  CHECK(RunBinary("bench tetra --kinds sideways --out " + (dir / "o").string(), dir, &err) == 2);
  // A bad structure parameter stops the run, whatever structures it times.
  CHECK(RunBinary("bench tetra --accel bvh --octree-mailbox maybe --out " + (dir / "o").string(), dir, &err) == 2);
  CHECK(err.find("--octree-mailbox 'maybe': expected on or off") != std::string::npos);
  CHECK(!fs::exists(dir / "o" / "results.json"));
  fs::remove_all(dir);
}

TEST_CASE("bench: a scene without lights skips its shadow rows and runs the rest")
{
  const fs::path dir = TempDir("nolight");
  const fs::path scene = dir / "dark.nff";
  std::ofstream(scene) << "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 16 16\n"
                          "f 1 1 1 1 0 0 0 1\ns 0 0 0 1\n";
  std::string err;
  const fs::path out = dir / "o";
  REQUIRE(RunBinary(fmt::format("bench {} --backend scalar --accel bvh --kinds primary,shadow --rays 256 --repeat 1 "
                                "--no-images --no-plots --no-stats --out {}",
                                scene.string(), out.string()),
                    dir, &err) == 0);
  CHECK(err.find("no shadow rays") != std::string::npos);
  CHECK(err.find("the scene has no point light") != std::string::npos);
  std::ifstream in(out / "results.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  int primary = 0, shadowSkipped = 0;
  for (const auto& r : j["rows"]) {
    if (r["kind"] == "primary" && r["error"].is_object() && r["error"]["wrong"] == 0) ++primary;
    // The note says why: no point light to cast shadow rays to.
    if (r["kind"] == "shadow" && r.value("note", std::string()).find("skipped") == 0 &&
        r.value("note", std::string()).find("no point light") != std::string::npos)
      ++shadowSkipped;
  }
  CHECK(primary == 1);
  CHECK(shadowSkipped == 1);
  fs::remove_all(dir);
}

TEST_CASE("bench: the SDF axis runs a scene with SDF blocks once per eps x relaxation x budget")
{
  const fs::path dir = TempDir("sdfaxis");
  const std::string scenes = test::SourcePath("scenes/geometry/sdf.nff") + " " + test::SourcePath("scenes/spd/tetra.nff");
  REQUIRE(RunBinary("bench " + scenes +
                        " --backend simd --accel bvh --precision robust --kinds primary --rays 1024 --repeat 1 "
                        "--no-images --no-plots --no-stats --sdf-eps 0.01,0.001 --sdf-relax 1,1.8 --sdf-steps 512 --out " +
                        (dir / "o").string(),
                    dir) == 0);
  std::ifstream in(dir / "o" / "results.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  std::set<std::string> names;
  for (const auto& r : j["rows"]) {
    names.insert(r["scene"].get<std::string>());
    CHECK(r["error"]["wrong"] == 0);
  }
  // The block scene four times (eps x relaxation, its budget replaced),
  // tetra (no blocks) once, as written.
  CHECK(names == std::set<std::string>{"sdf@eps=0.01,w=1,steps=512", "sdf@eps=0.01,w=1.8,steps=512",
                                       "sdf@eps=0.001,w=1,steps=512", "sdf@eps=0.001,w=1.8,steps=512", "tetra"});
  std::string err;
  CHECK(RunBinary("bench tetra --sdf-relax 2 --out " + (dir / "o").string(), dir, &err) == 2);
  fs::remove_all(dir);
}

TEST_CASE("bench: timed runs in rounds over a scene's rows by default, back to back with --no-interleave")
{
  const fs::path dir = TempDir("interleave");
  const std::string common = "bench tetra --backend scalar,simd --accel grid,bvh --precision robust --kinds primary,shadow "
                             "--rays 512 --repeat 3 --no-images --no-plots --no-stats --out ";
  std::string errA, errB;
  REQUIRE(RunBinary(common + (dir / "a").string(), dir, &errA) == 0);
  REQUIRE(RunBinary(common + (dir / "b").string() + " --no-interleave", dir, &errB) == 0);
  CHECK(errA.find("tetra: 12 rows built and checked; timing them in 3 interleaved rounds") != std::string::npos);
  CHECK(errB.find("interleaved rounds") == std::string::npos);
  const auto load = [&](const char* name) {
    std::ifstream in(dir / name / "results.json");
    return nlohmann::json::parse(in);
  };
  const nlohmann::json a = load("a"), b = load("b");
  CHECK(a["options"]["interleave"] == true);
  CHECK(b["options"]["interleave"] == false);
  // The same rows in the same order, the same answers, three timed runs
  // each, and each configuration's memory its own.
  REQUIRE(a["rows"].size() == 12);  // scalar grid, bvh; simd grid, bvh (auto, single, packet) x 2 kinds
  REQUIRE(b["rows"].size() == a["rows"].size());
  for (std::size_t i = 0; i < a["rows"].size(); ++i) {
    const auto &ra = a["rows"][i], &rb = b["rows"][i];
    INFO("row ", i);
    CHECK(ra["backend"] == rb["backend"]);
    CHECK(ra["accel"] == rb["accel"]);
    CHECK(ra["kind"] == rb["kind"]);
    CHECK(ra["hits"] == rb["hits"]);
    CHECK(ra["error"]["wrong"] == 0);
    CHECK(ra["repeat"] == 3);
    CHECK(rb["repeat"] == 3);
    CHECK(ra["interleaved"] == true);
    CHECK(rb["interleaved"] == false);
    CHECK(ra["trace_ms"]["min"].get<double>() > 0.0);
    CHECK(ra["trace_ms"]["min"].get<double>() <= ra["trace_ms"]["max"].get<double>());
    CHECK(ra["variant"] == rb["variant"]);
  }
  fs::remove_all(dir);
}

TEST_CASE("bench: configurations planned by default and from lists")
{
  bench::BenchOptions o;
  const auto all = bench::PlanCombos(o, true, true);
  std::set<std::string> labels;
  for (const auto& c : all) labels.insert(c.Label());
  for (const char* l : {"simd grid", "simd octree", "simd bvh", "simd hgrid", "opencl grid", "opencl bvh ray",
                        "opencl hgrid", "opencl bvh stackless", "opencl bvh wide", "scalar bvh fast",
                        "scalar bvh fp64", "simd bvh fast", "opencl bvh fp64"})
    CHECK(labels.count(l) == 1);
  // The OpenCL BVH's stack walk is a named row: unnamed, it would be the
  // device's default walk (wide on PoCL), a second "opencl bvh wide".
  CHECK(labels.count("opencl bvh") == 0);
  // The SIMD BVH's walks by name beside auto's, robust only.
  CHECK(labels.count("simd bvh single") == 1);
  CHECK(labels.count("simd bvh packet") == 1);
  CHECK(labels.count("simd bvh single fast") == 0);
  CHECK(labels.count("embree packet8") == (EmbreeAvailable() ? 1u : 0u));
  CHECK(labels.count("embree single robust") == (EmbreeAvailable() ? 1u : 0u));

  // Without OpenCL or fp64 on the device, those rows are not planned.
  for (const auto& c : bench::PlanCombos(o, false, false)) CHECK(c.backend != Backend::OpenCL);
  for (const auto& c : bench::PlanCombos(o, false, true))
    CHECK_FALSE((c.backend == Backend::OpenCL && c.precision == Precision::Fp64));

  // Explicit lists: their cross product, modes a backend lacks left out.
  o.backends = {Backend::Simd, Backend::Scalar};
  o.accels = {AccelKind::BVH};
  o.precisions = {Precision::Fast, Precision::Fp64};
  std::set<std::string> got;
  for (const auto& c : bench::PlanCombos(o, true, true)) got.insert(c.Label());
  CHECK(got == std::set<std::string>{"simd bvh fast", "scalar bvh fast", "scalar bvh fp64"});
}

TEST_CASE("bench: ours against Embree, ratio of speeds")
{
  auto row = [](const char* backend, const char* label, const char* kind, double mrays) {
    return nlohmann::json{{"scene", "balls"},   {"kind", kind},     {"backend", backend},
                          {"label", label},     {"precision", std::string(backend) == "embree" ? "embree" : "robust"},
                          {"mrays_per_s", {{"median", mrays}, {"min", mrays}, {"max", mrays}}}};
  };
  nlohmann::json rows = nlohmann::json::array();
  rows.push_back(row("simd", "simd bvh", "primary", 12.0));
  rows.push_back(row("simd", "simd grid", "primary", 3.0));
  rows.push_back(row("embree", "embree single", "primary", 4.0));
  rows.push_back(row("embree", "embree packet8", "primary", 8.0));
  const std::string md = bench::EmbreeComparisonMarkdown(rows, {"primary"});
  INFO(md);
  CHECK(md.find("| balls | primary | simd bvh | 12.00 | embree packet8 | 8.00 | 1.50 |") != std::string::npos);
  nlohmann::json none = nlohmann::json::array({row("simd", "simd bvh", "primary", 1.0)});
  CHECK(bench::EmbreeComparisonMarkdown(none, {"primary"}).empty());
}
