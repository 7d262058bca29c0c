// Shared helpers for the test suite: scene paths, cached scenes, ray sets, and
// the conformance check of any tracer against the fp64 reference.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <unistd.h>

#include <doctest/doctest.h>

#include "host/cl/cl_device.h"
#include "host/core/error.h"
#include "host/io/rays_io.h"
#include "host/rays/raygen.h"
#include "host/reference/check.h"
#include "host/reference/reference.h"
#include "host/render/renderer.h"
#include "host/scene/scene.h"
#include "host/trace/tracer.h"

namespace cr::test {

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
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

// The build tree (the cellray binary is in <build>/bin).
inline std::filesystem::path BuildDir() { return std::filesystem::path(CELLRAY_BINARY).parent_path().parent_path(); }

// OpenCL programs built by the tests persist under the build tree
// (test-cache/opencl), so only the first run pays for the compiler.
inline ScopedEnv OpenCLTestCacheDir()
{
  return ScopedEnv("CELLRAY_CACHE_DIR", (BuildDir() / "test-cache" / "opencl").string());
}

// The scenes a loop over SPD scenes visits: `defaults`, unless the
// environment variable CELLRAY_TEST_SCENES names others (comma-separated SPD
// names). The sanitizer run sets it (CMakePresets.json, test preset "asan") to
// a few small scenes that hold every primitive type: under ASan + UBSan the
// builds and traversals of all 11 scenes cost more than its CI budget.
inline std::vector<std::string> Scenes(std::vector<std::string> defaults)
{
  const char* env = std::getenv("CELLRAY_TEST_SCENES");
  if (!env || !*env) return defaults;
  std::vector<std::string> names;
  std::string_view list(env);
  while (!list.empty()) {
    const std::size_t comma = list.find(',');
    if (comma != 0) names.emplace_back(list.substr(0, comma));
    list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
  }
  return names;
}

// The 11 SPD scenes shipped in scenes/spd/ (or those of CELLRAY_TEST_SCENES).
inline const std::vector<std::string>& SpdScenes()
{
  static const std::vector<std::string> names = Scenes({"balls", "gears", "jacks", "lattice", "mount", "rings",
                                                        "shells", "sombrero", "teapot", "tetra", "tree"});
  return names;
}

// This test process's scratch folder, <tmp>/<prefix>_<pid>: made on first
// use, and removed with everything in it when the process exits (tests
// leave nothing behind in the system's temporary folder).
inline std::filesystem::path ProcessTempDir(const std::string& prefix)
{
  struct Dirs {
    std::mutex m;
    std::map<std::string, std::filesystem::path> paths;
    ~Dirs()
    {
      for (const auto& [name, path] : paths) {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
      }
    }
  };
  static Dirs dirs;
  std::lock_guard<std::mutex> lock(dirs.m);
  std::filesystem::path& d = dirs.paths[prefix];
  if (d.empty()) {
    d = std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
  }
  return d;
}

// A file's bytes (empty when it cannot be read).
inline std::string Slurp(const std::filesystem::path& p)
{
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A file in this process's scratch folder `prefix` (ProcessTempDir).
inline std::string TempPath(const std::string& name, const std::string& prefix = "cellray_test")
{
  return (ProcessTempDir(prefix) / name).string();
}

// The four ray kinds of the conformance checks.
inline constexpr RayKind kKinds[] = {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random};

// The distance in ulps between two floats (on the monotonic integer line of
// their bit patterns, negative floats counting down from -0).
inline std::int64_t UlpDistance(float a, float b)
{
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  const std::int64_t la = ia < 0 ? -std::int64_t(ia & 0x7FFFFFFF) : ia;
  const std::int64_t lb = ib < 0 ? -std::int64_t(ib & 0x7FFFFFFF) : ib;
  return la > lb ? la - lb : lb - la;
}

inline std::string SourcePath(const std::string& rel) { return std::string(CELLRAY_SOURCE_DIR) + "/" + rel; }
inline std::string SpdPath(const std::string& name) { return SourcePath("scenes/spd/" + name + ".nff"); }

// Loads each scene once per test process.
inline const Scene& CachedScene(const std::string& path)
{
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[path];
  if (!slot) slot = std::make_unique<Scene>(LoadScene(path));
  return *slot;
}

// A digest of the scene's primitives (FNV-1a over every type's array and
// the statement count): a scene built later at the address of a destroyed
// one (a local Scene in another test case of the same process) must not
// get the destroyed scene's reference.
inline std::uint64_t SceneDigest(const Scene& scene)
{
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  const std::uint32_t n = scene.NumPrims();
  mix(&n, sizeof n);
  scene.ForEachType([&](const auto& pieces, std::uint32_t) {
    const std::size_t count = pieces.size();
    mix(&count, sizeof count);
    if (count) mix(pieces.data(), count * sizeof(pieces[0]));
  });
  const std::vector<float> motion = scene.UnifiedMotion();
  if (!motion.empty()) mix(motion.data(), motion.size() * sizeof(float));
  return h;
}

inline const ref::ReferenceTracer& CachedReference(const Scene& scene)
{
  struct Entry {
    std::uint64_t digest = 0;
    std::unique_ptr<ref::ReferenceTracer> tracer;
  };
  static std::mutex mutex;
  static std::map<const Scene*, Entry> cache;
  std::lock_guard<std::mutex> lock(mutex);
  Entry& slot = cache[&scene];
  const std::uint64_t digest = SceneDigest(scene);
  if (!slot.tracer || slot.digest != digest) {
    slot.tracer = std::make_unique<ref::ReferenceTracer>(scene);
    slot.digest = digest;
  }
  return *slot.tracer;
}

// A ray set of the given kind with about size * size rays.
// times: for a scene with motion, the rays' times (GenerateRays).
inline std::vector<RayRecord> MakeRays(const Scene& scene, RayKind kind, int size, std::uint64_t seed = 7,
                                       std::vector<float>* times = nullptr)
{
  RayGenOptions g;
  g.kind = kind;
  g.width = size;
  g.height = size;
  g.seed = seed;
  g.count = std::uint64_t(size) * std::uint64_t(size);
  return GenerateRays(scene, CachedReference(scene), g, times);
}

inline bool IsOcclusion(RayKind kind) { return IsOcclusionKind(kind); }

// The rays whose answers differ: bit for bit, or for occlusion hit against
// miss (which primitive answers an any-hit query is the traversal's).
inline std::size_t CountDiffering(const std::vector<HitRecord>& a, const std::vector<HitRecord>& b, bool occlusion)
{
  REQUIRE(a.size() == b.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    differ += occlusion ? (a[i].prim == CR_NO_HIT) != (b[i].prim == CR_NO_HIT)
                        : std::memcmp(&a[i], &b[i], sizeof(HitRecord)) != 0;
  return differ;
}

// Traces `rays` with `config` and checks every answer against the reference.
inline ref::CheckResult CheckTracer(const Scene& scene, const TraceConfig& config, const std::vector<RayRecord>& rays,
                                    bool occlusion, std::vector<HitRecord>* hitsOut = nullptr,
                                    const std::vector<float>* times = nullptr)
{
  auto tracer = CreateTracer(scene, config);
  std::vector<HitRecord> hits;
  tracer->Trace(rays, times ? *times : Tracer::NoTimes(), hits, occlusion, nullptr);
  REQUIRE(hits.size() == rays.size());
  ref::CheckResult r = ref::CheckHits(CachedReference(scene), rays, hits, occlusion, times ? *times : Tracer::NoTimes());
  if (hitsOut) *hitsOut = std::move(hits);
  return r;
}

// Every structure x ray kind (primary, shadow, diffuse, random; `size`^2
// rays each) of one backend and precision against the fp64 reference:
// robust and fp64 must have no wrong answer; fast is reported (MESSAGE),
// not asserted.
inline void CheckConformance(const Scene& scene, const std::string& name, Backend backend, Precision precision,
                             int size)
{
  for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random}) {
    const auto rays = MakeRays(scene, kind, size);
    for (AccelKind accel : kAccelKinds) {
      TraceConfig cfg;
      cfg.backend = backend;
      cfg.accel = accel;
      cfg.precision = precision;
      auto r = CheckTracer(scene, cfg, rays, IsOcclusion(kind));
      const std::string what = name + " " + RayKindName(kind) + " " + AccelKindName(accel) + " " +
                               BackendName(backend) + " " + PrecisionName(precision) + ": " +
                               std::to_string(r.wrong) + " wrong of " + std::to_string(r.rays);
      INFO(what, r.firstWrong.empty() ? std::string() : " (first " + std::to_string(r.firstWrong[0]) + ")");
      CHECK(r.rays == rays.size());
      if (precision != Precision::Fast) CHECK(r.wrong == 0);
      else if (r.wrong) MESSAGE("reported, not asserted: ", what);
    }
  }
}

// Renders `scene` with a tracer of the given backend and structure.
inline Image RenderWith(const Scene& scene, Backend backend, AccelKind accel, const RenderOptions& ro,
                        RenderStats* st = nullptr)
{
  TraceConfig cfg;
  cfg.backend = backend;
  cfg.accel = accel;
  cfg.unifiedHits = true;
  auto tracer = CreateTracer(scene, cfg);
  return Render(scene, *tracer, ro, st);
}

// Whether an OpenCL device is present (a failure to list counts as none).
inline bool HaveOpenCLDevice()
{
  static const bool have = [] {
    try {
      return !ListClDevices().empty();
    } catch (const std::exception&) {
      return false;
    }
  }();
  return have;
}

// Every traversal path of the backends here: scalar, the SIMD packet and
// single-ray walks, and OpenCL per ray and packet where a device is present.
struct TracePath {
  const char* name;
  Backend backend;
  const char* variant;
};
inline std::vector<TracePath> TracePaths()
{
  std::vector<TracePath> paths = {{"scalar", Backend::Scalar, ""},
                                  {"simd packet", Backend::Simd, "packet"},
                                  {"simd single", Backend::Simd, "single"}};
  if (HaveOpenCLDevice()) {
    paths.push_back({"opencl ray", Backend::OpenCL, "ray"});
    paths.push_back({"opencl packet", Backend::OpenCL, "packet"});
  }
  return paths;
}

// The OpenCL programs a conformance check of `precision` runs: robust the
// ones specialised to the scene's types (what `cellray trace` builds), fp64
// the every-type programs (CELLRAY_CL_TYPES=all) that the hard-case suite
// builds too: the same primitive code, and 8 fewer PoCL compiles per type
// set in a fresh CI (about 25 s of CPU each time).
inline ScopedEnv ConformanceProgramTypes(Precision precision)
{
  return ScopedEnv("CELLRAY_CL_TYPES", precision == Precision::Fp64 ? "all" : "scene");
}

// A primitive's OpenCL conformance, robust and fp64, on its scenes (name,
// scene), with the tests' program cache; a message, no check, without an
// OpenCL device.
inline void CheckOpenCLConformance(std::initializer_list<std::pair<const char*, const Scene*>> scenes, int size)
{
  if (!HaveOpenCLDevice()) {
    MESSAGE("SKIPPED: no OpenCL device");
    return;
  }
  const auto cache = OpenCLTestCacheDir();
  for (Precision p : {Precision::Robust, Precision::Fp64}) {
    const auto types = ConformanceProgramTypes(p);
    for (const auto& [name, scene] : scenes) CheckConformance(*scene, name, Backend::OpenCL, p, size);
  }
}

// The SIMD backend (single and packet) answers as the scalar kernels do, bit
// for bit, in robust and (unless !fastToo) fast precision, for every ray
// kind on the scene.
inline void CheckSimdEqualsScalar(const Scene& scene, int size, bool fastToo = true)
{
  for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random}) {
    const auto rays = MakeRays(scene, kind, size);
    for (Precision p : {Precision::Robust, Precision::Fast}) {
      if (p == Precision::Fast && !fastToo) continue;
      TraceConfig sc;
      sc.backend = Backend::Scalar;
      sc.precision = p;
      std::vector<HitRecord> want, got;
      CreateTracer(scene, sc)->Trace(rays, want, IsOcclusion(kind), nullptr);
      for (const char* variant : {"single", "packet"}) {
        TraceConfig cfg = sc;
        cfg.backend = Backend::Simd;
        cfg.variant = variant;
        CreateTracer(scene, cfg)->Trace(rays, got, IsOcclusion(kind), nullptr);
        INFO(RayKindName(kind), " ", PrecisionName(p), " ", variant);
        CHECK(CountDiffering(want, got, IsOcclusion(kind)) == 0);
      }
    }
  }
}

// Parsing `text` (as file "bad.nff") is bad input whose message holds `what`.
inline void CheckNffError(const std::string& text, const char* what)
{
  Scene bad;
  try {
    ParseNFF(text, "bad.nff", bad);
  } catch (const InputError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find(what) != std::string::npos);
    return;
  }
  FAIL("no error for: ", text);
}

}  // namespace cr::test
