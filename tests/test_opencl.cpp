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

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cl/cl_context.h"
#include "cl/cl_device.h"
#include "cl/cl_error.h"
#include "cl/cl_program_cache.h"
#include "core/error.h"
#include "scene/camera.h"
#include "test_util.h"

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

// The build tree (the cellray binary is in <build>/bin).
fs::path BuildDir() { return fs::path(CELLRAY_BINARY).parent_path().parent_path(); }

// Sets an environment variable for the scope of a test.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name)
  {
    if (const char* old = std::getenv(name)) old_ = old;
    had_ = std::getenv(name) != nullptr;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv()
  {
    if (had_)
      ::setenv(name_, old_.c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

// Programs built by the tests persist under the build tree.
ScopedEnv TestCacheDir() { return ScopedEnv("CELLRAY_CACHE_DIR", (BuildDir() / "test-cache" / "opencl").string()); }

std::int64_t UlpDistance(float a, float b)
{
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  if (ia < 0) ia = std::int32_t(0x80000000u - std::uint32_t(ia));
  if (ib < 0) ib = std::int32_t(0x80000000u - std::uint32_t(ib));
  return std::llabs(std::int64_t(ia) - std::int64_t(ib));
}

struct Comparison {
  std::size_t differ = 0;        // different answer, not explained
  std::size_t exactTies = 0;     // different primitive at exactly the same t
  std::size_t otherOccluder = 0; // occlusion: occluded by another primitive (any hit is right)
  std::string firstDiffer;
};

// Compares OpenCL hits with the scalar backend's: same primitive, t within
// 2 ulp, same u, v within 2 ulp; for occlusion the same verdict.
Comparison Compare(const std::vector<HitRecord>& cl, const std::vector<HitRecord>& sc, bool occlusion)
{
  Comparison c;
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

const RayKind kKinds[] = {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random};
constexpr int kRaySize = 24;  // 576 rays per scene and kind

// Every SPD scene x ray kind with `accel`, for the ray and packet variants.
void RunConformance(AccelKind accel)
{
  auto cache = TestCacheDir();
  std::size_t ties = 0, otherOccluders = 0;
  const std::vector<std::string> variants = {"ray", "packet"};
  for (const std::string& name : test::SpdScenes()) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    TraceConfig sc;
    sc.backend = Backend::Scalar;
    sc.accel = accel;
    auto scalar = CreateTracer(scene, sc);
    for (const std::string& variant : variants) {
      TraceConfig cfg = sc;
      cfg.backend = Backend::OpenCL;
      cfg.variant = variant;
      auto tracer = CreateTracer(scene, cfg);
      for (RayKind kind : kKinds) {
        const bool occlusion = test::IsOcclusion(kind);
        const auto rays = test::MakeRays(scene, kind, kRaySize);
        std::vector<HitRecord> hits, ref;
        tracer->Trace(rays, hits, occlusion, nullptr);
        scalar->Trace(rays, ref, occlusion, nullptr);
        const Comparison c = Compare(hits, ref, occlusion);
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

std::vector<char> Slurp(const fs::path& p)
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

  const std::vector<char> good = Slurp(key.file);
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
  CHECK_THROWS_AS(SelectClDevice(std::to_string(all.size())), InputError);
  CHECK_THROWS_AS(SelectClDevice("0:999"), InputError);
  CHECK_THROWS_AS(SelectClDevice("gpu"), InputError);
  {
    ScopedEnv env("CELLRAY_DEVICE", "7:7");
    CHECK_THROWS_AS(SelectClDevice(""), InputError);
  }
  // A buffer larger than one allocation may be is refused before allocating.
  CHECK_THROWS_AS(ClCheckAllocation(all[0], "test buffer", all[0].maxAllocBytes + 1), RuntimeError);
  CHECK_NOTHROW(ClCheckAllocation(all[0], "test buffer", 1024));
}

TEST_CASE("opencl: conformance, bvh, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunConformance(AccelKind::BVH);
}

TEST_CASE("opencl: conformance, grid, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunConformance(AccelKind::Grid);
}

TEST_CASE("opencl: conformance, octree, ray and packet variants, every SPD scene x ray kind" *
          doctest::skip(NoOpenCL()))
{
  RunConformance(AccelKind::Octree);
}

TEST_CASE("opencl: primary rays generated on the device equal the host's" * doctest::skip(NoOpenCL()))
{
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("teapot"));
  const int w = 40, h = 30;
  RayGenOptions g;
  g.width = w;
  g.height = h;
  const auto rays = GenerateRays(scene, test::CachedReference(scene), g);
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
    if (fp64) CHECK(Compare(hits, ref, false).differ == 0);
  }
}

TEST_CASE("opencl: statistics and unified hits" * doctest::skip(NoOpenCL()))
{
  auto cache = TestCacheDir();
  const Scene& scene = test::CachedScene(test::SpdPath("mount"));
  const auto rays = test::MakeRays(scene, RayKind::Diffuse, 20);
  for (AccelKind accel : {AccelKind::BVH, AccelKind::Grid, AccelKind::Octree}) {
    TraceConfig sc;
    sc.accel = accel;
    sc.stats = true;
    sc.unifiedHits = true;
    TraceStatsSum scalarStats;
    std::vector<HitRecord> ref;
    CreateTracer(scene, sc)->Trace(rays, ref, false, &scalarStats);
    for (const char* variant : {"ray", "packet"}) {
      TraceConfig cfg = sc;
      cfg.backend = Backend::OpenCL;
      cfg.variant = variant;
      TraceStatsSum stats;
      std::vector<HitRecord> hits;
      CreateTracer(scene, cfg)->Trace(rays, hits, false, &stats);
      INFO(std::string(AccelKindName(accel)), " ", variant);
      CHECK(Compare(hits, ref, false).differ == 0);  // unified ids and barycentrics of every piece
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
  for (AccelKind accel : {AccelKind::BVH, AccelKind::Grid, AccelKind::Octree})
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
    CHECK(Compare(hits, ref, false).differ == 0);
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
  const std::vector<char> good = Slurp(files[0]);

  Spit(files[0], std::vector<char>(good.begin(), good.begin() + good.size() / 2));
  CHECK(run(&note) == "miss");
  CHECK(note.find("truncated") != std::string::npos);
  CHECK(Slurp(files[0]).size() > kClCacheHeaderBytes);  // replaced by a fresh entry...
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
