// Distributed ray tracing and the path tracer against closed forms: the
// irradiance of a parallelogram light (Lambert's polygon formula) with and
// without an occluder's penumbra, the thin lens's circle of confusion, the
// convergence of the one-bounce integrators to each other at least at the
// rate 1 / sqrt(spp), and the same image on every structure and backend.
#include <cmath>

#include <fmt/format.h>

#include "host/render/image_io.h"
#include "host/render/renderer.h"
#include "host/scene/camera.h"
#include "tests/test_util.h"

using namespace cr;

namespace {


// Irradiance at x (normal n) from a convex polygon of radiance L, all of it
// above x's plane: E = L/2 sum_i angle(r_i, r_i+1) n . unit(r_i x r_i+1)
// (Lambert 1760), the polygon's vertices seen from x.
double PolygonIrradiance(const glm::dvec3& x, const glm::dvec3& n, const std::vector<glm::dvec3>& poly, double L)
{
  double sum = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const glm::dvec3 a = glm::normalize(poly[i] - x), b = glm::normalize(poly[(i + 1) % poly.size()] - x);
    const glm::dvec3 c = glm::cross(a, b);
    const double lc = glm::length(c);
    if (lc == 0.0) continue;
    sum += std::atan2(lc, glm::dot(a, b)) * glm::dot(n, c / lc);
  }
  return 0.5 * L * std::fabs(sum);
}

double Mean(const std::vector<float>& v)
{
  double s = 0.0;
  for (float x : v) s += x;
  return s / double(v.size());
}

double Rmse(const Image& a, const Image& b)
{
  double s = 0.0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) s += double(a.rgb[i] - b.rgb[i]) * double(a.rgb[i] - b.rgb[i]);
  return std::sqrt(s / double(a.rgb.size()));
}

}  // namespace

TEST_CASE("area light: the image of a white plane is its irradiance over pi (Lambert's formula), penumbra included")
{
  // A unit-radiance 1 x 1 light at height 1 beside the view (x in 1.5..2.5),
  // emitting down onto the plane z = 0 of albedo 1, seen from straight above;
  // optionally a blade at height 0.5 (x in 0.9..1.3, outside the view) whose
  // shadow's penumbra crosses the viewed square.
  const std::string view = "b 0 0 0\nv\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 20\nhither 0.01\nresolution 48 48\n"
                           "la 1.5 -0.5 1  0 1 0  1 0 0  1 1 1\n"
                           "f 1 1 1 1 0 0 0 1\np 4\n-3 -3 0\n3 -3 0\n3 3 0\n-3 3 0\n";
  const std::string blade = "p 4\n0.9 -20 0.5\n0.9 20 0.5\n1.3 20 0.5\n1.3 -20 0.5\n";
  for (bool occluded : {false, true}) {
    Scene scene;
    ParseNFF(view + (occluded ? blade : ""), "area", scene);
    REQUIRE(scene.areaLights.size() == 1);
    CHECK(scene.areaLights[0].n.z == doctest::Approx(-1.0));
    RenderOptions ro;
    ro.spp = occluded ? 1024 : 256;  // the penumbra breaks the light's stratification
    Image img = test::RenderWith(scene, Backend::Simd, AccelKind::BVH, ro);
    const CameraFrame f = MakeCameraFrame(scene.camera, img.width, img.height);
    double serr = 0.0, err = 0.0, ref = 0.0, lo = 1e9, hi = 0.0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        // The renderer's pixel is a box over its footprint: the closed form
        // averaged over 8 x 8 points of it.
        double E = 0.0;
        glm::dvec3 p(0.0);
        for (int sy = 0; sy < 8; ++sy)
          for (int sx = 0; sx < 8; ++sx) {
            const RayRecord r = PrimaryRay(f, x - 0.5 + (sx + 0.5) / 8.0, y - 0.5 + (sy + 0.5) / 8.0);
            const double t = -double(r.org[2]) / double(r.dir[2]);
            p = glm::dvec3(r.org[0] + t * r.dir[0], r.org[1] + t * r.dir[1], 0.0);
            // The light's part that the blade leaves visible from p: the ray to
            // light point X crosses height 0.5 at (p.x + X) / 2, blocked in
            // [0.9, 1.3], so X in [1.8 - p.x, 2.6 - p.x] is hidden.
            std::vector<std::pair<double, double>> parts{{1.5, 2.5}};
            if (occluded) parts = {{1.5, std::min(2.5, 1.8 - p.x)}, {std::max(1.5, 2.6 - p.x), 2.5}};
            for (auto [x0, x1] : parts)
              if (x1 > x0)
                E += PolygonIrradiance(p, {0, 0, 1}, {{x0, -0.5, 1}, {x1, -0.5, 1}, {x1, 0.5, 1}, {x0, 0.5, 1}}, 1.0) / 64.0;
          }
        const double expect = E / 3.14159265358979323846;
        const double got = img.rgb[(std::size_t(y) * img.width + x) * 3];
        err += std::fabs(got - expect);
        serr += got - expect;
        ref += expect;
        lo = std::min(lo, expect);
        hi = std::max(hi, expect);
      }
    INFO(std::string(occluded ? "penumbra" : "open"), ": mean |error| / mean ", err / ref, ", mean error / mean ", serr / ref, ", irradiance/pi from ", lo, " to ", hi);
    CHECK(err / ref < 0.01);
    CHECK(std::fabs(serr / ref) < 0.002);  // no bias beneath the noise
    if (occluded) CHECK(lo < 0.5 * hi);  // the penumbra is in view
  }
}

TEST_CASE("thin lens: a point's circle of confusion has the thin-lens diameter, and the focal plane is sharp")
{
  // A tiny sphere light at depth z on the axis; focus at 4, aperture radius
  // 0.1: the rays through the lens meet the focal plane in a disc of radius
  // A |1 - f / z| (similar triangles), whose second moment is r^2 / 2.
  for (double z : {2.0, 4.0, 8.0}) {
    const double A = 0.1, focal = 4.0, s = 0.004;
    Scene scene;
    ParseNFF(fmt::format("b 0 0 0\nv\nfrom 0 0 0\nat 0 0 -1\nup 0 1 0\nangle 6\nhither 0.01\nresolution 128 128\n"
                         "lens {} {}\nls 0 0 {} {} 1 1 1\n",
                         A, focal, -z, s),
             "lens", scene);
    RenderOptions ro;
    ro.spp = 256;
    Image img = test::RenderWith(scene, Backend::Simd, AccelKind::BVH, ro);
    double m0 = 0, mx = 0, my = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const double v = img.rgb[(std::size_t(y) * img.width + x) * 3];
        m0 += v, mx += v * x, my += v * y;
      }
    mx /= m0, my /= m0;
    double m2 = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        m2 += img.rgb[(std::size_t(y) * img.width + x) * 3] * ((x - mx) * (x - mx) + (y - my) * (y - my));
    m2 /= m0;
    // Pixel units at the focal plane; the sphere's own image (radius s f / z)
    // and the pixel's box add their second moments.
    const double tanHalf = std::tan(3.0 * 3.14159265358979323846 / 180.0);
    const double px = focal * 2.0 * tanHalf / 127.0;
    const double R = A * std::fabs(1.0 - focal / z) / px, S = s * focal / z / px;
    const double measured = std::sqrt(std::max(0.0, 2.0 * (m2 - 1.0 / 6.0) - S * S));
    INFO("z ", z, ": circle of confusion radius ", measured, " px, thin lens ", R, " px");
    CHECK(mx == doctest::Approx(63.5).epsilon(0.01));
    if (R > 1.0)
      CHECK(measured == doctest::Approx(R).epsilon(0.02));
    else
      CHECK(measured < 1.0);
  }
}

TEST_CASE("diffuse interreflection: --diffuse cosine:K and cube:N converge to the path tracer limited to two bounces")
{
  // On a diffuse-only scene the first hit's gather (one bounce) and a path
  // of two vertices model the same light transport; both are unbiased, so
  // their error against a high-spp path render falls as 1 / sqrt(spp).
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/distributed/cornell_diffuse.nff"));
  RenderOptions base;
  base.width = base.height = 40;
  base.maxDepth = 2;
  RenderOptions refOpt = base;
  refOpt.integrator = Integrator::Path;
  refOpt.spp = 4096;
  refOpt.seed = 99;
  const Image ref = test::RenderWith(scene, Backend::Simd, AccelKind::BVH, refOpt);
  CHECK(Mean(ref.rgb) > 0.05);
  struct Setup {
    const char* name;
    Integrator integrator;
    DiffuseGather diffuse;
  };
  const Setup setups[] = {{"path --depth 2", Integrator::Path, {}},
                          {"whitted --diffuse cosine:4", Integrator::Whitted, ParseDiffuse("cosine:4")},
                          {"whitted --diffuse cube:2", Integrator::Whitted, ParseDiffuse("cube:2")}};
  for (const Setup& s : setups) {
    double e[3];
    const int spps[3] = {4, 16, 64};
    for (int i = 0; i < 3; ++i) {
      RenderOptions ro = base;
      ro.integrator = s.integrator;
      ro.diffuse = s.diffuse;
      ro.spp = spps[i];
      e[i] = Rmse(test::RenderWith(scene, Backend::Simd, AccelKind::BVH, ro), ref);
    }
    const double slope = std::log(e[2] / e[0]) / std::log(16.0);
    INFO(std::string(s.name), ": RMSE ", e[0], " ", e[1], " ", e[2], " at 4, 16, 64 spp, slope ", slope);
    // Stratified samples (pixel, light, first bounce) converge faster than
    // independent ones: at least as fast as 1 / sqrt(spp), and no bias
    // floor (the error keeps falling to 64 spp).
    CHECK(slope < -0.45);
    CHECK(slope > -1.0);
    CHECK(e[2] < e[1]);
  }
}

TEST_CASE("the new scenes render to the same image on every structure and backend as on the fp64 reference")
{
  const auto guard = test::OpenCLTestCacheDir();
  struct Setup {
    const char* scene;
    const char* name;
    Integrator integrator;
    const char* diffuse;
  };
  // The Cornell box with both integrators, the lens and the motion-blurred
  // scenes with the path tracer.
  const Setup setups[] = {{"cornell", "path", Integrator::Path, ""},
                          {"cornell", "whitted cube:2", Integrator::Whitted, "cube:2"},
                          {"dof", "path", Integrator::Path, ""},
                          {"motion", "path", Integrator::Path, ""}};
  std::vector<Backend> backends{Backend::Scalar, Backend::Simd};
  if (test::HaveOpenCLDevice()) backends.push_back(Backend::OpenCL);
  for (const Setup& s : setups) {
    const Scene& scene = test::CachedScene(test::SourcePath(fmt::format("scenes/distributed/{}.nff", s.scene)));
    RenderOptions ro;
    ro.width = ro.height = 48;
    ro.spp = 4;
    ro.integrator = s.integrator;
    if (*s.diffuse) ro.diffuse = ParseDiffuse(s.diffuse);
    const Image ref = test::RenderWith(scene, Backend::Reference, AccelKind::BVH, ro);
    CHECK(Mean(ref.rgb) > 0.02);
    for (Backend backend : backends)
      for (AccelKind accel : {AccelKind::Grid, AccelKind::Octree, AccelKind::BVH}) {
        const Image img = test::RenderWith(scene, backend, accel, ro);
        const ImageDiff d = CompareImages(img.width, img.height, img.rgb, ref.rgb);
        INFO(std::string(s.scene), " ", std::string(s.name), " ", std::string(BackendName(backend)), " ",
             std::string(AccelKindName(accel)), ": PSNR ", d.psnr, " dB, ", d.nDiffering, " pixels differ");
        CHECK(d.psnr >= 60.0);
      }
  }
}

TEST_CASE("render: --time-limit stops after whole passes, --write-every delivers the image so far")
{
  const Scene& scene = test::CachedScene(test::SourcePath("scenes/distributed/cornell.nff"));
  RenderOptions ro;
  ro.width = ro.height = 32;
  ro.integrator = Integrator::Path;
  ro.spp = 4;
  ro.writeEvery = 1;
  std::vector<int> seen;
  ro.onImage = [&](const Image& img, int passes) {
    CHECK(img.width == 32);
    seen.push_back(passes);
  };
  RenderStats st;
  const Image full = test::RenderWith(scene, Backend::Simd, AccelKind::BVH, ro, &st);
  CHECK(st.passes == 4);
  CHECK(seen == std::vector<int>{1, 2, 3});
  CHECK_FALSE(st.timeLimited);
  ro.spp = 65536;
  ro.writeEvery = 0;
  ro.timeLimit = 0.3;
  const Image part = test::RenderWith(scene, Backend::Simd, AccelKind::BVH, ro, &st);
  CHECK(st.timeLimited);
  CHECK(st.passes >= 1);
  CHECK(st.passes < 65536);
  CHECK(Mean(part.rgb) == doctest::Approx(Mean(full.rgb)).epsilon(0.2));
}

TEST_CASE("NFF area lights and lens: ids in file order, errors with file and line")
{
  Scene scene;
  ParseNFF("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0\nresolution 8 8\nlens 0.2 5\n"
           "s 0 0 0 1\nla 0 0 2 1 0 0 0 1 0 3 3 3\nls 0 3 0 0.5 1 2 3\ns 1 1 1 1\n",
           "lights", scene);
  CHECK(scene.camera.aperture == doctest::Approx(0.2f));
  CHECK(scene.camera.focal == doctest::Approx(5.0f));
  REQUIRE(scene.NumPrims() == 4);
  REQUIRE(scene.areaLights.size() == 2);
  CHECK(scene.areaLights[0].prim == 1);
  CHECK(scene.areaLights[1].prim == 2);
  CHECK(scene.MaterialOf(1).light == 0);
  CHECK(scene.MaterialOf(2).emission.b == doctest::Approx(3.0f));
  CHECK(scene.MaterialOf(3).light == -1);
  test::CheckNffError("la 0 0 0 1 0 0 2 0 0 1 1 1\n", "no area");
  test::CheckNffError("la 0 0 0 1 0 0 0 1 0 1 -1 1\n", "negative");
  test::CheckNffError("ls 0 0 0 0 1 1 1\n", "radius");
  test::CheckNffError("ls 0 0 0 1 1 1\n", "radiance");
  test::CheckNffError("lens 0.1 2\n", "before the 'v'");
  test::CheckNffError("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0\nresolution 8 8\nlens 0.1 0\n", "focal");
}

TEST_CASE("soft-shadow and path rays: every structure x backend, robust and fp64, 0 wrong against the reference")
{
  const auto guard = test::OpenCLTestCacheDir();
  std::vector<Backend> backends{Backend::Scalar, Backend::Simd};
  if (test::HaveOpenCLDevice()) backends.push_back(Backend::OpenCL);
  for (const std::string& path : {test::SourcePath("scenes/distributed/cornell.nff"), test::SpdPath("balls")}) {
    const Scene& scene = test::CachedScene(path);
    for (RayKind kind : {RayKind::Soft, RayKind::Path}) {
      const auto rays = test::MakeRays(scene, kind, 40);
      CHECK(rays.size() > 1000u);
      for (Backend backend : backends)
        for (Precision precision : {Precision::Robust, Precision::Fp64})
          for (AccelKind accel : {AccelKind::Grid, AccelKind::Octree, AccelKind::BVH}) {
            TraceConfig cfg;
            cfg.backend = backend;
            cfg.accel = accel;
            cfg.precision = precision;
            const auto r = test::CheckTracer(scene, cfg, rays, IsOcclusionKind(kind));
            INFO(path, " ", std::string(RayKindName(kind)), " ", std::string(BackendName(backend)), " ",
                 std::string(AccelKindName(accel)), " ", std::string(PrecisionName(precision)), ": ", r.wrong,
                 " wrong of ", r.rays);
            CHECK(r.rays == rays.size());
            CHECK(r.wrong == 0);
          }
    }
  }
}
