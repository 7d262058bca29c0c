// Motion blur (NFF `motion`, CRRAYS02 ray times): a sphere moving across the
// frame covers each pixel for the time the closed form gives; rays with
// times are answered right on every structure x backend; the formats and
// the statement's errors.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <unistd.h>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/io/rays_io.h"
#include "host/render/renderer.h"
#include "host/scene/camera.h"
#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;

namespace {

// The fraction of the shutter [0, 1] during which the ray o + t d (t > 0)
// passes through the sphere of radius r whose centre moves from c0 to
// c0 + D: the perpendicular offset a + tau b of the centre from the ray's
// line is below r on the roots of |b|^2 tau^2 + 2 a.b tau + |a|^2 - r^2.
double TimeCoverage(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& c0, const glm::dvec3& D, double r)
{
  const glm::dvec3 u = glm::normalize(d);
  const glm::dvec3 w = c0 - o;
  const glm::dvec3 a = w - glm::dot(w, u) * u, b = D - glm::dot(D, u) * u;
  const double A = glm::dot(b, b), B = glm::dot(a, b), C = glm::dot(a, a) - r * r;
  if (A == 0.0) return C < 0.0 ? 1.0 : 0.0;
  const double disc = B * B - A * C;
  if (disc <= 0.0) return 0.0;
  const double s = std::sqrt(disc);
  const double t0 = std::max(0.0, (-B - s) / A), t1 = std::min(1.0, (-B + s) / A);
  return std::max(0.0, t1 - t0);
}

std::string MotionTempPath(const std::string& name) { return test::TempPath(name, "cellray_motion"); }

// Many small moving triangles and spheres, each with its own motion, and a
// static ground: leaves and cells hold pieces of mixed motions.
std::string MovingCrowd(int n, std::uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-4.0, 4.0), mv(-1.5, 1.5), size(0.05, 0.4);
  std::string s = "v\nfrom 0 3 12\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 64\nl 4 8 6\n"
                  "f 0.8 0.8 0.8 0.8 0.2 20 0 1\np 4\n-9 -5 -9\n9 -5 -9\n9 -5 9\n-9 -5 9\n";
  for (int i = 0; i < n; ++i) {
    s += fmt::format("motion {} {} {}\n", mv(rng), mv(rng), i % 5 == 0 ? 0.0 : mv(rng));
    const double x = pos(rng), y = pos(rng), z = pos(rng), e = size(rng);
    if (i % 3 == 0)
      s += fmt::format("s {} {} {} {}\n", x, y, z, e);
    else
      s += fmt::format("p 3\n{} {} {}\n{} {} {}\n{} {} {}\n", x, y, z, x + e, y, z + 0.3 * e, x, y + e, z - 0.5 * e);
    if (i % 7 == 0) s += "motion 0 0 0\n";  // some static ones among them
  }
  return s;
}

}  // namespace

TEST_CASE("motion blur: a sphere moving across the frame covers each pixel for the analytic time")
{
  // A black sphere of radius 0.5 moving by 3 along x before a white
  // background, no light: a pixel's value is 1 - its coverage, averaged
  // over the pixel's area and the shutter. The closed form (TimeCoverage)
  // integrated over each pixel on a 16 x 16 grid is the expected image.
  const glm::dvec3 c0(-1.5, 0.2, 0.0), D(3.0, 0.0, 0.0);
  const double r = 0.5;
  Scene scene;
  ParseNFF(fmt::format("b 1 1 1\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 24\nhither 0.01\nresolution 64 24\n"
                       "f 0 0 0 0 0 0 0 1\nmotion {} {} {}\ns {} {} {} {}\n",
                       D.x, D.y, D.z, c0.x, c0.y, c0.z, r),
           "motion", scene);
  const int w = 64, h = 24;
  const CameraFrame frame = MakeCameraFrame(scene.camera, w, h);
  std::vector<double> expect(std::size_t(w) * h);
  constexpr int kSub = 16;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double cov = 0.0;
      for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
          const RayRecord ray = PrimaryRay(frame, x - 0.5 + (i + 0.5) / kSub, y - 0.5 + (j + 0.5) / kSub);
          cov += TimeCoverage(glm::dvec3(ray.org[0], ray.org[1], ray.org[2]),
                              glm::dvec3(ray.dir[0], ray.dir[1], ray.dir[2]), c0, D, r);
        }
      expect[std::size_t(y) * w + x] = 1.0 - cov / (kSub * kSub);
    }
  std::vector<Backend> backends{Backend::Reference, Backend::Scalar, Backend::Simd};
  if (test::HaveOpenCLDevice()) backends.push_back(Backend::OpenCL);
  const auto guard = test::OpenCLTestCacheDir();
  for (Backend backend : backends) {
    RenderOptions ro;
    ro.spp = 256;
    const Image img = test::RenderWith(scene, backend, AccelKind::BVH, ro);
    REQUIRE(img.width == w);
    double sumErr = 0.0, maxErr = 0.0, sumImg = 0.0, sumExp = 0.0;
    int partial = 0;
    for (std::size_t p = 0; p < expect.size(); ++p) {
      const double v = img.rgb[3 * p];
      CHECK(img.rgb[3 * p + 1] == img.rgb[3 * p]);
      const double e = std::fabs(v - expect[p]);
      sumErr += e;
      maxErr = std::max(maxErr, e);
      sumImg += 1.0 - v;
      sumExp += 1.0 - expect[p];
      partial += expect[p] > 0.02 && expect[p] < 0.98;
    }
    const double meanErr = sumErr / double(expect.size());
    INFO(std::string(BackendName(backend)), ": mean |error| ", meanErr, ", max ", maxErr, ", covered ", sumImg,
         " pixels against ", sumExp, " analytic, ", partial, " partly covered pixels");
    CHECK(partial > 100);  // the blur spreads the sphere's edge over many pixels
    CHECK(meanErr < 0.004);
    CHECK(maxErr < 0.08);
    CHECK(sumImg == doctest::Approx(sumExp).epsilon(0.005));
  }
}

TEST_CASE("motion blur: rays with times, every structure x backend, robust and fp64, 0 wrong against the reference")
{
  const auto guard = test::OpenCLTestCacheDir();
  std::vector<Backend> backends{Backend::Scalar, Backend::Simd};
  if (test::HaveOpenCLDevice()) backends.push_back(Backend::OpenCL);
  Scene crowd;
  ParseNFF(MovingCrowd(400, 5), "crowd", crowd);
  REQUIRE(crowd.hasMotion);
  const Scene& motion = test::CachedScene(test::SourcePath("scenes/distributed/motion.nff"));
  for (const Scene* scene : {&motion, static_cast<const Scene*>(&crowd)}) {
    for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random, RayKind::Soft}) {
      if (kind == RayKind::Shadow && scene->lights.empty()) continue;  // motion.nff has an area light only
      std::vector<float> times;
      const auto rays = test::MakeRays(*scene, kind, 32, 7, &times);
      REQUIRE(times.size() == rays.size());
      CHECK(rays.size() > 500u);
      for (Backend backend : backends)
        for (Precision precision : {Precision::Robust, Precision::Fp64}) {
          const auto types = test::ConformanceProgramTypes(precision);  // OpenCL: both scenes share fp64's
          for (AccelKind accel : kAccelKinds)
            // SIMD: the packet and single-ray walks (the default picks one).
            for (const char* variant : {"packet", "single"}) {
              if (backend != Backend::Simd && variant[0] == 's') continue;
              TraceConfig cfg;
              cfg.backend = backend;
              cfg.accel = accel;
              cfg.precision = precision;
              if (backend == Backend::Simd) cfg.variant = variant;
              const auto r = test::CheckTracer(*scene, cfg, rays, IsOcclusionKind(kind), nullptr, &times);
              INFO(scene->path, " ", std::string(RayKindName(kind)), " ", std::string(BackendName(backend)), " ",
                   std::string(AccelKindName(accel)), " ", std::string(PrecisionName(precision)), " ", cfg.variant,
                   ": ", r.wrong, " wrong of ", r.rays);
              CHECK(r.rays == rays.size());
              CHECK(r.wrong == 0);
            }
        }
      // Embree (the bench baseline): two time steps, its own BVH.
      if (EmbreeAvailable())
        for (const char* variant : {"single", "packet8"}) {
          TraceConfig cfg;
          cfg.backend = Backend::Embree;
          cfg.variant = variant;
          const auto r = test::CheckTracer(*scene, cfg, rays, IsOcclusionKind(kind), nullptr, &times);
          INFO(scene->path, " ", std::string(RayKindName(kind)), " embree ", std::string(variant), ": ", r.wrong,
               " wrong of ", r.rays);
          CHECK(r.wrong == 0);
        }
    }
  }
}

TEST_CASE("motion blur: the checker sees a tracer that ignores the times")
{
  // The same rays traced at time 0 are not the answers at their times: the
  // check must report wrong answers (the test above cannot pass vacuously).
  const Scene& motion = test::CachedScene(test::SourcePath("scenes/distributed/motion.nff"));
  std::vector<float> times;
  const auto rays = test::MakeRays(motion, RayKind::Primary, 48, 7, &times);
  TraceConfig cfg;
  cfg.backend = Backend::Scalar;
  auto tracer = CreateTracer(motion, cfg);
  std::vector<HitRecord> hits;
  tracer->Trace(rays, hits, false, nullptr);
  const auto r = ref::CheckHits(test::CachedReference(motion), rays, hits, false, times);
  INFO(r.wrong, " wrong of ", r.rays);
  CHECK(r.wrong > 20u);
}

TEST_CASE("motion: swept bounds, NFF errors, CRRAYS02 round trip and rejections")
{
  Scene scene;
  ParseNFF("motion 1 0 0\ns 0 0 0 1\nmotion 0 0 0\ns 5 0 0 1\n", "m", scene);
  REQUIRE(scene.NumPrims() == 2);
  CHECK(scene.hasMotion);
  CHECK(scene.prims[0].motion == glm::vec3(1.0f, 0.0f, 0.0f));
  CHECK(scene.prims[1].motion == glm::vec3(0.0f));
  const Bounds b = scene.UnifiedBounds(0);
  CHECK(b.lo.x <= -1.0f);
  CHECK(b.hi.x >= 2.0f);
  CHECK(b.hi.x < 2.001f);
  CHECK(scene.UnifiedBounds(1).lo.x >= 3.999f);
  CHECK(scene.UnifiedMotion().size() == 8u);
  test::CheckNffError("motion 1 0\ns 0 0 0 1\n", "motion");
  test::CheckNffError("motion 1 0 0\nls 0 3 0 0.5 1 2 3\n", "cannot move");

  const std::vector<RayRecord> rays = {RayRecord{{0, 0, 0}, 0, {0, 0, 1}, INFINITY},
                                       RayRecord{{1, 2, 3}, 0.5f, {0, 1, 0}, 9}};
  const std::string p = MotionTempPath("timed.rays");
  WriteRays(p, rays, {0.25f, 1.0f});
  CHECK(FileSize(p) == 16 + 36 * 2);
  CHECK(std::string(ReadFile(p).data(), 8) == "CRRAYS02");
  std::vector<float> times;
  const auto back = ReadRays(p, &times);
  REQUIRE(back.size() == 2u);
  CHECK(std::memcmp(back.data(), rays.data(), sizeof(RayRecord) * 2) == 0);
  CHECK(times == std::vector<float>{0.25f, 1.0f});
  // A reader that takes no times refuses a file whose times matter.
  CHECK_THROWS_AS(ReadRays(p), InputError);
  // CRRAYS01 still reads, with no times (time 0).
  const std::string p1 = MotionTempPath("plain.rays");
  WriteRays(p1, rays);
  CHECK(ReadRays(p1, &times).size() == 2u);
  CHECK(times.empty());
  // A time outside [0, 1] is refused with the record's index.
  {
    std::ofstream out(p, std::ios::binary);
    const std::uint64_t n = 1;
    out.write("CRRAYS02", 8);
    out.write(reinterpret_cast<const char*>(&n), 8);
    out.write(reinterpret_cast<const char*>(&rays[0]), sizeof(RayRecord));
    const float bad = 1.5f;
    out.write(reinterpret_cast<const char*>(&bad), 4);
  }
  try {
    ReadRays(p, &times);
    FAIL("no error for a time of 1.5");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("not in [0, 1]") != std::string::npos);
  }
}
