// The OpenCL backend on whatever device the machine has (PoCL's CPU device in
// CI): conformance against the scalar backend (same primitives, t within 2
// ulp) and the fp64 reference (0 wrong), for every SPD scene, structure, ray
// kind and variant; the program cache's defences; the runtime's errors.
//
// Without an OpenCL device the device tests are skipped, and say so on stderr
// when the test binary starts (doctest's skip decorator is decided then).
// Compiled programs are cached under the build tree (test-cache/opencl), so
// only the first run pays for the compiler.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/cl/cl_context.h"
#include "host/cl/cl_device.h"
#include "host/cl/cl_error.h"
#include "host/cl/cl_options.h"
#include "host/cl/cl_program.h"
#include "host/cl/cl_program_cache.h"
#include "host/core/error.h"
#include "host/render/image_io.h"
#include "host/scene/camera.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

// True when no OpenCL device can be used; prints why, once, on stderr.
bool NoOpenCL()
{
  static const bool none = [] {
    std::string why;
    try {
      if (!ListClDevices().empty()) return false;
      why = "the OpenCL platforms offer no device";
    } catch (const std::exception& e) {
      why = e.what();
    }
    std::fprintf(stderr, "cellray_tests: *** OpenCL device tests SKIPPED: %s ***\n", why.c_str());
    return true;
  }();
  return none;
}

namespace fs = std::filesystem;
using cr::test::BuildDir;
using cr::test::kKinds;
using cr::test::UlpDistance;

// The build tree (the cellray binary is in <build>/bin).

using test::ScopedEnv;

ScopedEnv TestCacheDir() { return test::OpenCLTestCacheDir(); }

// The host's camera rays of a w x h image of the scene (what the device's
// camera kernels generate).
std::vector<RayRecord> HostCameraRays(const Scene& scene, int w, int h)
{
  RayGenOptions g;
  g.width = w;
  g.height = h;
  return GenerateRays(scene, test::CachedReference(scene), g);
}

struct ClComparison {
  std::size_t differ = 0;        // different answer, not explained
  std::size_t exactTies = 0;     // different primitive at exactly the same t
  std::size_t otherOccluder = 0; // occlusion: occluded by another primitive (any hit is right)
  std::string firstDiffer;
};

// Compares OpenCL hits with the scalar backend's: same primitive, t within
// 2 ulp, same u, v within 2 ulp; for occlusion the same verdict.
ClComparison CompareCl(const std::vector<HitRecord>& cl, const std::vector<HitRecord>& sc, bool occlusion)
{
  ClComparison c;
  REQUIRE(cl.size() == sc.size());
  for (std::size_t i = 0; i < cl.size(); ++i) {
    const HitRecord& a = cl[i];
    const HitRecord& b = sc[i];
    bool same;
    if (occlusion) {
      same = (a.prim == CR_NO_HIT) == (b.prim == CR_NO_HIT);
      if (same && a.prim != b.prim) ++c.otherOccluder;
    } else if (a.prim != b.prim) {
      same = a.t == b.t && a.prim != CR_NO_HIT && b.prim != CR_NO_HIT;
      if (same) ++c.exactTies;
    } else {
      same = a.prim == CR_NO_HIT || (UlpDistance(a.t, b.t) <= 2 && UlpDistance(a.u, b.u) <= 2 &&
                                     UlpDistance(a.v, b.v) <= 2);
    }
    if (!same && c.differ++ == 0)
      c.firstDiffer = fmt::format("ray {}: opencl (t {}, prim {}) scalar (t {}, prim {})", i, a.t, a.prim, b.t, b.prim);
  }
  return c;
}

constexpr int kRaySize = 24;  // 576 rays per scene and kind

// Every SPD scene x ray kind with `accel`, for the ray and packet variants
// (and the BVH's stackless, wide and wide-packet walks; the wide walks' binary BVH is
// built with the SIMD backend's parameters, BackendAccelParams, and so is
// the scalar side it is compared with).
void RunClConformance(AccelKind accel)
{
  auto cache = TestCacheDir();
  std::size_t ties = 0, otherOccluders = 0;
  std::vector<std::string> variants = {"ray", "packet"};
  if (accel == AccelKind::BVH) variants.insert(variants.end(), {"stackless", "wide", "wide-packet"});
  for (const std::string& name : test::SpdScenes()) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    TraceConfig sc;
    sc.backend = Backend::Scalar;
    sc.accel = accel;
    for (const std::string& variant : variants) {
      TraceConfig cfg = sc;
      cfg.backend = Backend::OpenCL;
      cfg.variant = variant;
      TraceConfig scalarCfg = sc;
      scalarCfg.params = BackendAccelParams(scene, cfg);
      auto scalar = CreateTracer(scene, scalarCfg);
      auto tracer = CreateTracer(scene, cfg);
      for (RayKind kind : kKinds) {
        const bool occlusion = test::IsOcclusion(kind);
        const auto rays = test::MakeRays(scene, kind, kRaySize);
        std::vector<HitRecord> hits, ref;
        tracer->Trace(rays, hits, occlusion, nullptr);
        scalar->Trace(rays, ref, occlusion, nullptr);
        const ClComparison c = CompareCl(hits, ref, occlusion);
        const ref::CheckResult r = ref::CheckHits(test::CachedReference(scene), rays, hits, occlusion);
        INFO(name, " ", std::string(RayKindName(kind)), " ", std::string(AccelKindName(accel)), " opencl ", variant, ": ", c.differ,
             " differ from scalar (", c.firstDiffer, "), ", r.wrong, " wrong of ", r.rays);
        CHECK(r.rays == rays.size());
        CHECK(c.differ == 0);
        CHECK(r.wrong == 0);
        ties += c.exactTies;
        otherOccluders += c.otherOccluder;
      }
    }
  }
  MESSAGE("opencl vs scalar, ", std::string(AccelKindName(accel)), ": ", ties, " rays with an exact tie answered by another "
          "primitive, ", otherOccluders, " occlusion rays with another (valid) occluder");
}

// The .clbin files of a cache directory.
std::vector<fs::path> CacheFiles(const fs::path& dir)
{
  std::vector<fs::path> out;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".clbin") out.push_back(e.path());
  return out;
}

std::vector<char> SlurpBytes(const fs::path& p)
{
  std::ifstream in(p, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void Spit(const fs::path& p, const std::vector<char>& data)
{
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(data.data(), std::streamsize(data.size()));
}

}  // namespace

TEST_CASE("opencl: error codes are reported by name with the call site")
{
  CHECK(ClErrorName(-52) == "CL_INVALID_KERNEL_ARGS");
  CHECK(ClErrorName(-11) == "CL_BUILD_PROGRAM_FAILURE");
  CHECK(ClErrorName(-1001) == "CL_PLATFORM_NOT_FOUND_KHR");
  CHECK(ClErrorName(-9999).find("-9999") != std::string::npos);
  try {
    CR_CL_CHECK(-54, "clEnqueueNDRangeKernel");
    FAIL("no exception");
  } catch (const RuntimeError& e) {
    const std::string what = e.what();
    CHECK(what.find("clEnqueueNDRangeKernel") != std::string::npos);
    CHECK(what.find("CL_INVALID_WORK_GROUP_SIZE") != std::string::npos);
    CHECK(what.find("test_opencl.cpp:") != std::string::npos);
  }
}

TEST_CASE("opencl: program cache entries are checked before use (no device needed)")
{
  const fs::path dir = BuildDir() / "test-cache" / fmt::format("unit-{}", ::getpid());
  fs::remove_all(dir);
  const ClCacheKey key = MakeClCacheKey(dir.string(), "kernel source", "dev", "drv 1", "OpenCL 1.2", "-DX");
  std::vector<unsigned char> bin(1000);
  for (std::size_t i = 0; i < bin.size(); ++i) bin[i] = static_cast<unsigned char>(i * 7);
  CHECK_FALSE(LoadClCache(key).binary);
  CHECK(LoadClCache(key).why == "absent");
  REQUIRE(StoreClCache(key, bin));
  auto hit = LoadClCache(key);
  REQUIRE(hit.binary);
  CHECK(*hit.binary == bin);

  // Any change of the key is another entry.
  const ClCacheKey other = MakeClCacheKey(dir.string(), "kernel source", "dev", "drv 2", "OpenCL 1.2", "-DX");
  CHECK(other.file != key.file);
  CHECK_FALSE(LoadClCache(other).binary);

  const std::vector<char> good = SlurpBytes(key.file);
  SUBCASE("truncated payload")
  {
    Spit(key.file, std::vector<char>(good.begin(), good.end() - 10));
    auto r = LoadClCache(key);
    CHECK_FALSE(r.binary);
    CHECK(r.corrupt);
    CHECK(r.why.find("truncated") != std::string::npos);
  }
  SUBCASE("truncated header")
  {
    Spit(key.file, std::vector<char>(good.begin(), good.begin() + 20));
    auto r = LoadClCache(key);
    CHECK_FALSE(r.binary);
    CHECK(r.why == "truncated header");
  }
  SUBCASE("flipped payload byte")
  {
    auto bad = good;
    bad[bad.size() - 500] ^= 0x10;
    Spit(key.file, bad);
    auto r = LoadClCache(key);
    CHECK_FALSE(r.binary);
    CHECK(r.why == "bad payload checksum");
  }
  SUBCASE("flipped header byte")
  {
    auto bad = good;
    bad[33] ^= 0x01;  // payload size
    Spit(key.file, bad);
    auto r = LoadClCache(key);
    CHECK_FALSE(r.binary);
    CHECK(r.why == "bad header checksum");
  }
  SUBCASE("another version of the format")
  {
    auto bad = good;
    bad[8] = 99;
    Spit(key.file, bad);
    CHECK_FALSE(LoadClCache(key).binary);
  }
  SUBCASE("an entry for another key under this name")
  {
    REQUIRE(StoreClCache(other, bin));
    fs::copy_file(other.file, key.file, fs::copy_options::overwrite_existing);
    auto r = LoadClCache(key);
    CHECK_FALSE(r.binary);
    CHECK(r.why == "stale (key differs)");
  }
  // A rewrite repairs the entry.
  REQUIRE(StoreClCache(key, bin));
  CHECK(LoadClCache(key).binary);
  fs::remove_all(dir);
}

TEST_CASE("opencl: no platform is a clear runtime error (exit 1), not a crash")
{
  const fs::path err = BuildDir() / "test-cache" / fmt::format("noplatform-{}.txt", ::getpid());
  fs::create_directories(err.parent_path());
  const std::string rays = (BuildDir() / "test-cache" / "noplatform.rays").string();
  {
    const Scene& scene = test::CachedScene(test::SpdPath("jacks"));
    WriteRays(rays, test::MakeRays(scene, RayKind::Primary, 4));
  }
  const std::string cmd = fmt::format("OCL_ICD_VENDORS=/nonexistent-dir {} trace {} --rays {} --backend opencl "
                                      "> /dev/null 2> {}",
                                      CELLRAY_BINARY, test::SpdPath("jacks"), rays, err.string());
  const int status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == kExitRuntime);
  std::ifstream in(err);
  std::string line, all;
  int lines = 0;
  while (std::getline(in, line)) {
    all += line;
    ++lines;
  }
  INFO("stderr: ", all);
  CHECK(lines == 1);
  CHECK(all.find("no platform") != std::string::npos);
  fs::remove(err);
}

TEST_CASE("opencl: device choice" * doctest::skip(NoOpenCL()))
{
  const auto all = ListClDevices();
  REQUIRE(!all.empty());
  CHECK(SelectClDevice("0").name == all[0].name);
  CHECK(SelectClDevice(fmt::format("{}:{}", all[0].platformIndex, all[0].deviceIndex)).flatIndex == 0);
  // A well-formed name of a device this machine lacks is a runtime error
  // (CL_DEVICE_NOT_FOUND: `auto` falls back from it); a malformed one is
  // bad input.
  CHECK_THROWS_AS(SelectClDevice(std::to_string(all.size())), RuntimeError);
  CHECK_THROWS_AS(SelectClDevice("0:999"), RuntimeError);
  CHECK_THROWS_AS(SelectClDevice("gpu"), InputError);
  CHECK_THROWS_AS(SelectClDevice("1:x"), InputError);
  {
    ScopedEnv env("CELLRAY_DEVICE", "7:7");
    CHECK_THROWS_AS(SelectClDevice(""), RuntimeError);
  }
  // A buffer larger than one allocation may be is refused before allocating.
  CHECK_THROWS_AS(ClCheckAllocation(all[0], "test buffer", all[0].maxAllocBytes + 1), RuntimeError);
  CHECK_NOTHROW(ClCheckAllocation(all[0], "test buffer", 1024));
}

TEST_CASE("opencl: conformance, bvh, ray, packet, stackless, wide and wide-packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunClConformance(AccelKind::BVH);
}

TEST_CASE("opencl: conformance, grid, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunClConformance(AccelKind::Grid);
}

TEST_CASE("opencl: conformance, octree, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunClConformance(AccelKind::Octree);
}

TEST_CASE("opencl: conformance, hgrid, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunClConformance(AccelKind::HGrid);
}

TEST_CASE("opencl: primary rays generated on the device equal the host's" * doctest::skip(NoOpenCL()))
{
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("teapot"));
  const int w = 40, h = 30;
  const auto rays = HostCameraRays(scene, w, h);
  TraceConfig sc;
  std::vector<HitRecord> ref;
  CreateTracer(scene, sc)->Trace(rays, ref, false, nullptr);
  const bool fp64 = SelectClDevice("").fp64;
  for (const char* variant : {"ray", "packet"}) {
    TraceConfig cfg;
    cfg.backend = Backend::OpenCL;
    cfg.variant = variant;
    auto tracer = CreateTracer(scene, cfg);
    std::vector<HitRecord> hits;
    tracer->TracePrimary(MakeCameraFrame(scene.camera, w, h), w, h, hits, nullptr);
    REQUIRE(hits.size() == rays.size());
    const ref::CheckResult r = ref::CheckHits(test::CachedReference(scene), rays, hits, false);
    INFO(variant);
    CHECK(r.wrong == 0);
    std::size_t nHit = 0;
    for (const auto& x : hits) nHit += x.prim != CR_NO_HIT;
    CHECK(nHit > rays.size() / 4);
    // With fp64 the device computes the rays in double as the host does:
    // the same rays, so the same answers bit for bit.
    if (fp64) CHECK(CompareCl(hits, ref, false).differ == 0);
  }
}

TEST_CASE("opencl: each trace reports its kernel's device time, within the wall time" * doctest::skip(NoOpenCL()))
{
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("teapot"));
  RayGenOptions g;
  g.width = 64;
  g.height = 48;
  const auto rays = GenerateRays(scene, test::CachedReference(scene), g);
  TraceConfig sc;
  auto simd = CreateTracer(scene, sc);
  std::vector<HitRecord> hits;
  simd->Trace(rays, hits, false, nullptr);
  CHECK(simd->LastKernelMs() < 0.0);  // no device clock: none reported
  TraceConfig cfg;
  cfg.backend = Backend::OpenCL;
  auto tracer = CreateTracer(scene, cfg);
  tracer->Prepare(false);
  CHECK(tracer->LastKernelMs() < 0.0);  // the compile's empty launches are not traces
  for (bool occlusion : {false, true}) {
    const auto t0 = std::chrono::steady_clock::now();
    tracer->Trace(rays, hits, occlusion, nullptr);
    const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    INFO("occlusion " << occlusion);
    CHECK(tracer->LastKernelMs() > 0.0);
    CHECK(tracer->LastKernelMs() <= wallMs);
  }
  tracer->TracePrimary(MakeCameraFrame(scene.camera, 64, 48), 64, 48, hits, nullptr);
  CHECK(tracer->LastKernelMs() > 0.0);
}

TEST_CASE("opencl: statistics and unified hits" * doctest::skip(NoOpenCL()))
{
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("mount"));
  const auto rays = test::MakeRays(scene, RayKind::Diffuse, 20);
  for (AccelKind accel : kAccelKinds) {
    TraceConfig sc;
    sc.accel = accel;
    sc.stats = true;
    sc.unifiedHits = true;
    TraceStatsSum scalarStats;
    std::vector<HitRecord> ref;
    CreateTracer(scene, sc)->Trace(rays, ref, false, &scalarStats);
    for (const char* variant : {"ray", "packet", "stackless", "wide", "wide-packet"}) {
      TraceConfig cfg = sc;
      cfg.backend = Backend::OpenCL;
      cfg.variant = variant;
      const std::string v = variant;
      if ((v == "stackless" || v == "wide" || v == "wide-packet") && accel != AccelKind::BVH) {
        CHECK_THROWS_AS(CreateTracer(scene, cfg), InputError);  // the BVH's walk only
        continue;
      }
      TraceStatsSum stats;
      std::vector<HitRecord> hits;
      CreateTracer(scene, cfg)->Trace(rays, hits, false, &stats);
      INFO(std::string(AccelKindName(accel)), " ", variant);
      CHECK(CompareCl(hits, ref, false).differ == 0);  // unified ids and barycentrics of every piece
      CHECK(stats.rays == rays.size());
      CHECK(stats.nIT > 0);
      CHECK(stats.nTS > 0);
      // The per-ray kernels run the scalar backend's traversal, and so does
      // each lane of the grid packet (its own 3D-DDA): the same counts.
      if (std::string(variant) == "ray" || accel == AccelKind::Grid) {
        CHECK(stats.nIT == scalarStats.nIT);
        CHECK(stats.nTS == scalarStats.nTS);
        CHECK(stats.nLeaves == scalarStats.nLeaves);
        CHECK(stats.nEmptyLeaves == scalarStats.nEmptyLeaves);
      }
    }
  }
}

TEST_CASE("opencl: --device with two devices shares each batch and answers as one device" * doctest::skip(NoOpenCL()))
{
  // The machine's first device named twice: two contexts, the path that
  // --device all takes on a machine with two devices.
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("gears"));
  const auto rays = test::MakeRays(scene, RayKind::Diffuse, 300);  // 90,000 rays: several slices
  TraceConfig one;
  one.backend = Backend::OpenCL;
  one.device = "0";
  one.stats = true;
  TraceConfig two = one;
  two.device = "0,0";
  for (bool occlusion : {false, true}) {
    std::vector<HitRecord> a, b;
    TraceStatsSum sa, sb;
    CreateTracer(scene, one)->Trace(rays, a, occlusion, &sa);
    auto t = CreateTracer(scene, two);
    t->Trace(rays, b, occlusion, &sb);
    INFO("occlusion ", occlusion);
    CHECK(CompareCl(b, a, occlusion).differ == 0);
    CHECK(sb.rays == sa.rays);
    CHECK(sb.nIT == sa.nIT);
    nlohmann::json j;
    t->Describe(j);
    REQUIRE(j["devices"].size() == 2);
    int slices = 0;
    for (const auto& d : j["devices"]) slices += d["slices"].get<int>();
    CHECK(slices == 4 * 2);  // four slices per device per batch, taken as the devices come free
  }
  TraceConfig bad = one;
  bad.device = "0,,0";
  CHECK_THROWS_AS(CreateTracer(scene, bad), InputError);
}

TEST_CASE("opencl: a scene without primitives misses everywhere, every structure, packets" *
          doctest::skip(NoOpenCL()))
{
  // The generic programs model every primitive type: a packet must not read
  // a primitive (or a reference) that the scene does not have. (The per-ray
  // kernels read only what a leaf or cell lists.)
  auto cache = TestCacheDir();
  const Scene scene;
  std::vector<RayRecord> rays(40);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const float x = float(i) / float(rays.size());
    rays[i] = RayRecord{{x, 0.5f, -1.0f}, 0.0f, {0.1f * x, 0.0f, 1.0f}, CR_INF};
  }
  for (AccelKind accel : kAccelKinds)
    for (const char* variant : {"packet", "packet-generic"}) {
      TraceConfig cfg;
      cfg.backend = Backend::OpenCL;
      cfg.accel = accel;
      cfg.variant = variant;
      auto tracer = CreateTracer(scene, cfg);
      for (bool occlusion : {false, true}) {
        std::vector<HitRecord> hits;
        tracer->Trace(rays, hits, occlusion, nullptr);
        INFO(std::string(AccelKindName(accel)), " ", variant, occlusion ? " occlusion" : " closest");
        REQUIRE(hits.size() == rays.size());
        std::size_t nHit = 0;
        for (const auto& h : hits) nHit += h.prim != CR_NO_HIT;
        CHECK(nHit == 0);
      }
    }
}

TEST_CASE("opencl: the every-type program of the robust ray-margin octree's packet kernels builds and answers "
          "right" * doctest::skip(NoOpenCL()))
{
  // PoCL 3.1 crashed inside clBuildProgram (its work-group compile, LLVM's
  // InstCombine) on this program while the packet kernels declared their
  // local memory at kernel scope; they now take it as a __local argument
  // (kernels/trace.cl CR_PACKET_LOCALS, docs/OPENCL.md). Both packet
  // kernels: rays from a buffer and camera rays.
  auto cache = TestCacheDir();
  const test::ScopedEnv types("CELLRAY_CL_TYPES", "all");
  const Scene& scene = test::CachedScene(test::SpdPath("balls"));
  const int w = 24, h = 16;
  const auto camera = HostCameraRays(scene, w, h);
  const auto diffuse = test::MakeRays(scene, RayKind::Diffuse, 24);
  TraceConfig cfg;
  cfg.backend = Backend::OpenCL;
  cfg.accel = AccelKind::Octree;
  cfg.params.octreeMargin = "ray";
  cfg.variant = "packet";
  auto tracer = CreateTracer(scene, cfg);
  std::vector<HitRecord> hits;
  tracer->Trace(diffuse, hits, false, nullptr);
  REQUIRE(hits.size() == diffuse.size());
  CHECK(ref::CheckHits(test::CachedReference(scene), diffuse, hits, false).wrong == 0);
  tracer->TracePrimary(MakeCameraFrame(scene.camera, w, h), w, h, hits, nullptr);
  REQUIRE(hits.size() == camera.size());
  CHECK(ref::CheckHits(test::CachedReference(scene), camera, hits, false).wrong == 0);
  std::size_t nHit = 0;
  for (const auto& x : hits) nHit += x.prim != CR_NO_HIT;
  CHECK(nHit > camera.size() / 4);
}

TEST_CASE("opencl: a corrupt program cache entry is rebuilt, never trusted" * doctest::skip(NoOpenCL()))
{
  const fs::path dir = BuildDir() / "test-cache" / fmt::format("corrupt-{}", ::getpid());
  fs::remove_all(dir);
  ScopedEnv env("CELLRAY_CACHE_DIR", dir.string());
  SetWarningsQuiet(true);
  const Scene& scene = test::CachedScene(test::SpdPath("jacks"));
  const auto rays = test::MakeRays(scene, RayKind::Primary, 16);
  std::vector<HitRecord> ref;
  CreateTracer(scene, TraceConfig{})->Trace(rays, ref, false, nullptr);
  TraceConfig cfg;
  cfg.backend = Backend::OpenCL;

  // Builds a tracer, traces, and returns program_cache and its note.
  auto run = [&](std::string* note) {
    auto tracer = CreateTracer(scene, cfg);
    std::vector<HitRecord> hits;
    tracer->Trace(rays, hits, false, nullptr);
    CHECK(CompareCl(hits, ref, false).differ == 0);
    nlohmann::json j;
    tracer->Describe(j);
    if (note) *note = j.value("program_cache_note", "");
    return j["program_cache"].get<std::string>();
  };
  std::string note;
  CHECK(run(&note) == "miss");
  CHECK(note == "absent");
  auto files = CacheFiles(dir);
  REQUIRE(files.size() == 1);
  CHECK(run(nullptr) == "hit");
  const std::vector<char> good = SlurpBytes(files[0]);

  Spit(files[0], std::vector<char>(good.begin(), good.begin() + good.size() / 2));
  CHECK(run(&note) == "miss");
  CHECK(note.find("truncated") != std::string::npos);
  CHECK(SlurpBytes(files[0]).size() > kClCacheHeaderBytes);  // replaced by a fresh entry...
  CHECK(run(nullptr) == "hit");  // ...that is trusted

  auto flipped = good;
  for (std::size_t i = good.size() / 2; i < good.size() / 2 + 8; ++i) flipped[i] = char(~flipped[i]);
  Spit(files[0], flipped);
  CHECK(run(&note) == "miss");
  CHECK(note == "bad payload checksum");
  CHECK(run(nullptr) == "hit");

  Spit(files[0], std::vector<char>(10, 'x'));
  CHECK(run(&note) == "miss");
  CHECK(note == "truncated header");
  CHECK(run(nullptr) == "hit");
  SetWarningsQuiet(false);
  fs::remove_all(dir);
}

namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

// Runs `env <envs> cellray <args>`, capturing stdout and stderr.
CliRun RunCellray(const std::string& envs, const std::string& args, const fs::path& scratch)
{
  const fs::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd =
      fmt::format("env {} {} {} > {} 2> {}", envs, CELLRAY_BINARY, args, out.string(), err.string());
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const auto slurp = [](const fs::path& p) {
    const std::vector<char> v = SlurpBytes(p);
    return std::string(v.begin(), v.end());
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// The lines of `text` that cellray printed ("cellray: ..."); a driver may
// print its own (PoCL's compiler: "1 error generated.").
std::vector<std::string> CellrayLines(const std::string& text)
{
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string line;
  while (std::getline(ss, line))
    if (line.rfind("cellray:", 0) == 0) out.push_back(line);
  return out;
}

struct FaultCase {
  const char* fault;
  const char* error;  // the OpenCL error name the message carries
};
constexpr FaultCase kFaults[] = {{"build", "CL_BUILD_PROGRAM_FAILURE"},
                                 {"kernel", "CL_INVALID_KERNEL_NAME"},
                                 {"alloc", "CL_MEM_OBJECT_ALLOCATION_FAILURE"},
                                 {"launch", "CL_OUT_OF_RESOURCES"},
                                 {"device", "CL_DEVICE_NOT_AVAILABLE"},
                                 {"limits", "CL_INVALID_WORK_GROUP_SIZE"},
                                 {"localmem", "CL_OUT_OF_RESOURCES"}};

}  // namespace

TEST_CASE("opencl: every injected fault is a named error (exit 1) with --backend opencl and a simd fallback with "
          "--backend auto" *
          doctest::skip(NoOpenCL()))
{
  const fs::path dir = BuildDir() / "test-cache" / fmt::format("faults-{}", ::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path cache = dir / "cache";  // this test's own program cache: it must stay empty
  const std::string scene = test::SpdPath("jacks");
  const fs::path rays = dir / "jacks.rays", simdHits = dir / "simd.hits";
  WriteRays(rays.string(), test::MakeRays(test::CachedScene(scene), RayKind::Primary, 12));
  const std::string trace = fmt::format("trace {} --rays {} --variant packet", scene, rays.string());
  {
    const CliRun r = RunCellray("", fmt::format("{} --backend simd -o {}", trace, simdHits.string()), dir);
    REQUIRE(r.code == 0);
  }
  const std::vector<char> expected = SlurpBytes(simdHits);
  for (const FaultCase& fc : kFaults) {
    const std::string env = fmt::format("CELLRAY_CL_FAULT={} CELLRAY_CACHE_DIR={}", fc.fault, cache.string());
    const fs::path hits = dir / fmt::format("{}.hits", fc.fault);
    {
      const CliRun r = RunCellray(env, fmt::format("{} --backend opencl -o {}", trace, hits.string()), dir);
      INFO(fc.fault, " with --backend opencl: exit ", r.code, "\nstderr: ", r.err);
      CHECK(r.code == kExitRuntime);
      const auto lines = CellrayLines(r.err);
      REQUIRE(!lines.empty());
      CHECK(lines[0].rfind("cellray: OpenCL: ", 0) == 0);
      CHECK(lines[0].find(fc.error) != std::string::npos);
      CHECK(lines[0].find(fmt::format("[injected: CELLRAY_CL_FAULT={}]", fc.fault)) != std::string::npos);
      CHECK(r.out.empty());
      CHECK_FALSE(fs::exists(hits));  // no output file, not even a partial one
      if (std::string(fc.fault) == "build") {
        // The compiler's own log, with the line it stopped at.
        CHECK(r.err.find("--- build log of ") != std::string::npos);
        CHECK(r.err.find("build failure injected by CELLRAY_CL_FAULT=build") != std::string::npos);
      }
    }
    {
      // `auto` uses OpenCL on a CPU device only when one is named.
      const CliRun r = RunCellray(env, fmt::format("{} --backend auto --device 0 -o {}", trace, hits.string()), dir);
      INFO(fc.fault, " with --backend auto: exit ", r.code, "\nstderr: ", r.err, "\nstdout: ", r.out);
      CHECK(r.code == 0);
      const auto lines = CellrayLines(r.err);
      REQUIRE(lines.size() == 1);
      CHECK(lines[0].rfind("cellray: warning: OpenCL: ", 0) == 0);
      CHECK(lines[0].find(fc.error) != std::string::npos);
      CHECK(lines[0].find("falling back to the simd backend") != std::string::npos);
      const auto j = nlohmann::json::parse(r.out);
      CHECK(j["backend"] == "simd");
      CHECK(j["fallback_from"] == "opencl");
      CHECK(j["fallback_reason"].get<std::string>().find(fc.error) != std::string::npos);
      CHECK(SlurpBytes(hits) == expected);  // the simd backend's answers, bit for bit
    }
  }
  // No program of a failing build (or of one whose kernels could not be
  // created) is ever stored; the other faults strike after a good build,
  // whose program may be cached.
  {
    fs::remove_all(cache);
    for (const char* fault : {"build", "kernel"})
      for (const char* backend : {"opencl", "auto --device 0"})
        (void)RunCellray(fmt::format("CELLRAY_CL_FAULT={} CELLRAY_CACHE_DIR={}", fault, cache.string()),
                         fmt::format("{} --backend {}", trace, backend), dir);
    CHECK(CacheFiles(cache).empty());
  }
  // A device this machine does not have: a runtime error by name, and a
  // fallback for `auto`; a malformed device name stays bad input.
  {
    const CliRun r = RunCellray("", fmt::format("{} --backend opencl --device 99", trace), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == kExitRuntime);
    CHECK(r.err.find("CL_DEVICE_NOT_FOUND") != std::string::npos);
  }
  {
    const fs::path hits = dir / "missing.hits";
    const CliRun r = RunCellray("", fmt::format("{} --backend auto --device 99 -o {}", trace, hits.string()), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == 0);
    const auto lines = CellrayLines(r.err);
    REQUIRE(lines.size() == 1);
    CHECK(lines[0].find("CL_DEVICE_NOT_FOUND") != std::string::npos);
    CHECK(lines[0].find("falling back to the simd backend") != std::string::npos);
    CHECK(SlurpBytes(hits) == expected);
  }
  for (const char* backend : {"opencl", "auto"}) {
    const CliRun r = RunCellray("", fmt::format("{} --backend {} --device 0:x", trace, backend), dir);
    INFO(backend, " stderr: ", r.err);
    CHECK(r.code == kExitBadInput);
  }
  {
    const CliRun r = RunCellray("CELLRAY_CL_FAULT=build,bogus", fmt::format("{} --backend opencl", trace), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == kExitBadInput);
    CHECK(r.err.find("CELLRAY_CL_FAULT 'build,bogus': unknown fault 'bogus'") != std::string::npos);
  }
  // CELLRAY_CL_COLD: a bad value, and the inlined form on a CPU device
  // (PoCL's compiler crashes on some of it), are bad input by name; `call`
  // is what a CPU device builds anyway.
  for (const char* cold : {"bogus", "inline"}) {
    const CliRun r = RunCellray(fmt::format("CELLRAY_CL_COLD={}", cold),
                                fmt::format("{} --backend opencl", trace), dir);
    INFO(cold, " stderr: ", r.err);
    CHECK(r.code == kExitBadInput);
    CHECK(r.err.find(fmt::format("CELLRAY_CL_COLD={}", std::string(cold) == "bogus" ? "'bogus'" : "inline")) !=
          std::string::npos);
    CHECK(r.out.empty());
  }
  {
    const fs::path hits = dir / "cold-call.hits";
    const CliRun r = RunCellray("CELLRAY_CL_COLD=call",
                                fmt::format("{} --backend opencl -o {}", trace, hits.string()), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == 0);
    CHECK(SlurpBytes(hits) == expected);
  }
  // CELLRAY_CL_TYPES=all: a program with every primitive type, the same
  // answers; any value but scene or all is bad input by name.
  {
    const fs::path hits = dir / "types-all.hits";
    const CliRun r = RunCellray("CELLRAY_CL_TYPES=all",
                                fmt::format("{} --backend opencl -o {}", trace, hits.string()), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == 0);
    CHECK(SlurpBytes(hits) == expected);
    const std::string options = nlohmann::json::parse(r.out)["build_options"];
#define CR_HAS_ALL_(T, U, a) CHECK(options.find("-DCR_HAS_" #U "=1") != std::string::npos);
    CR_PRIM_TYPES(CR_HAS_ALL_)
#undef CR_HAS_ALL_
    const CliRun bad = RunCellray("CELLRAY_CL_TYPES=some", fmt::format("{} --backend opencl", trace), dir);
    CHECK(bad.code == kExitBadInput);
    CHECK(bad.err.find("CELLRAY_CL_TYPES='some': expected scene or all") != std::string::npos);
  }
  // A render falls back too (the first Trace fails), to the simd image.
  {
    const fs::path a = dir / "fallback.exr", b = dir / "simd.exr";
    const CliRun r = RunCellray(
        "CELLRAY_CL_FAULT=alloc",
        fmt::format("render {} --size 24x16 --no-progress --backend auto --device 0 -o {}", scene, a.string()), dir);
    INFO("stderr: ", r.err);
    CHECK(r.code == 0);
    CHECK(CellrayLines(r.err).size() == 1);
    CHECK(nlohmann::json::parse(r.out)["backend"] == "simd");
    REQUIRE(RunCellray("", fmt::format("render {} --size 24x16 --no-progress --backend simd -o {}", scene, b.string()),
                       dir)
                .code == 0);
    int wa = 0, ha = 0, wb = 0, hb = 0;
    CHECK(ReadImage(a.string(), wa, ha) == ReadImage(b.string(), wb, hb));
  }
  fs::remove_all(dir);
}

TEST_CASE("opencl: a cached program whose kernels cannot be created is removed and rebuilt" *
          doctest::skip(NoOpenCL()))
{
  // What a driver that compiles a program it cannot run leaves behind with
  // the old cache (which stored at the build): an entry that passes every
  // check of the file and yet yields no kernel. Made here by storing the
  // per-ray program's binary under the packet program's key.
  const fs::path dir = BuildDir() / "test-cache" / fmt::format("nokernel-{}", ::getpid());
  fs::remove_all(dir);
  ScopedEnv env("CELLRAY_CACHE_DIR", dir.string());
  SetWarningsQuiet(true);
  const Scene& scene = test::CachedScene(test::SpdPath("jacks"));
  const auto rays = test::MakeRays(scene, RayKind::Primary, 8);
  std::vector<HitRecord> ref;
  CreateTracer(scene, TraceConfig{})->Trace(rays, ref, false, nullptr);
  TraceConfig cfg;
  cfg.backend = Backend::OpenCL;
  const ClDevice dev = SelectClDevice("");
  auto keyOf = [&](const char* variant) {
    TraceConfig c = cfg;
    c.variant = variant;
    return MakeClCacheKey(dir.string(), ClKernelSource(), dev.name, dev.driverVersion, dev.platformVersion,
                          ClBuildOptions(MakeClProgramSpec(scene, c, false, false, dev), dev));
  };
  auto run = [&](const char* variant, std::string* note) {
    TraceConfig c = cfg;
    c.variant = variant;
    auto tracer = CreateTracer(scene, c);
    std::vector<HitRecord> hits;
    tracer->Trace(rays, hits, false, nullptr);
    CHECK(CompareCl(hits, ref, false).differ == 0);
    nlohmann::json j;
    tracer->Describe(j);
    if (note) *note = j.value("program_cache_note", "");
    return j["program_cache"].get<std::string>();
  };
  CHECK(run("ray", nullptr) == "miss");
  const ClCacheLookup rayProgram = LoadClCache(keyOf("ray"));
  REQUIRE(rayProgram.binary);
  const ClCacheKey packetKey = keyOf("packet");
  REQUIRE(StoreClCache(packetKey, *rayProgram.binary));
  REQUIRE(LoadClCache(packetKey).binary);  // a sound entry, as far as the file goes
  const long warnings = WarningCount();
  std::string note;
  CHECK(run("packet", &note) == "miss");
  CHECK(note.find("the driver rejected the cached binary (CL_INVALID_KERNEL_NAME at "
                  "clCreateKernel(Trace_RaysPacket))") != std::string::npos);
  CHECK(WarningCount() == warnings + 1);
  // Replaced by the rebuilt program, which is trusted from then on.
  CHECK(run("packet", nullptr) == "hit");
  SetWarningsQuiet(false);
  fs::remove_all(dir);
}
