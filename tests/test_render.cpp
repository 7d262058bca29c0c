// The Whitted renderer: SPD calibration, no self-shadowing on convex objects,
// and images that agree across structures and backends.
#include <cmath>

#include <fmt/format.h>

#include "host/render/image_io.h"
#include "host/render/renderer.h"
#include "tests/test_util.h"

using namespace cr;

namespace {


// A closed convex mesh: an icosahedron subdivided twice and pushed onto a
// sphere (320 triangles, outward winding), as NFF polygons.
std::string IcosphereNFF()
{
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4}, {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p = glm::normalize(p);
  for (int level = 0; level < 2; ++level) {
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      int m[3];
      for (int e = 0; e < 3; ++e) {
        v.push_back(glm::normalize(v[tri[e]] + v[tri[(e + 1) % 3]]));
        m[e] = int(v.size()) - 1;
      }
      g.push_back({tri[0], m[0], m[2]});
      g.push_back({tri[1], m[1], m[0]});
      g.push_back({tri[2], m[2], m[1]});
      g.push_back({m[0], m[1], m[2]});
    }
    f = g;
  }
  std::string s;
  for (auto& tri : f) {
    s += "p 3\n";
    for (int k : tri) s += fmt::format("{:.9g} {:.9g} {:.9g}\n", v[k].x * 2.0, v[k].y * 2.0, v[k].z * 2.0);
  }
  return s;
}

const char* kView =
    "b 0.2 0.3 0.5\nv\nfrom 0 -8 3\nat 0 0 0\nup 0 0 1\nangle 40\nhither 0.1\nresolution 96 96\n"
    "l 5 -6 8\nl -7 -3 2\nl 0 9 0\nf 0.9 0.8 0.7 0.8 0.3 20 0 0\n";

}  // namespace

TEST_CASE("render --spd on tetra reproduces the published SPD ray counts")
{
  const Scene& scene = test::CachedScene(test::SpdPath("tetra"));
  RenderOptions ro;
  ro.spd = true;
  RenderStats st;
  Image img = test::RenderWith(scene, Backend::Scalar, AccelKind::BVH, ro, &st);
  CHECK(img.width == 512);
  CHECK(st.eyeRays == 263169u);
  CHECK(double(st.eyeHits) == doctest::Approx(49788).epsilon(0.005));
  CHECK(st.reflectionRays == 0u);
  CHECK(st.refractionRays == 0u);
  CHECK(double(st.shadowRays) == doctest::Approx(46112).epsilon(0.01));
}

TEST_CASE("a convex opaque object lit from outside never shadows itself")
{
  // A sphere, a closed icosphere mesh, and a plane 10^4 units wide seen from
  // near its middle (a float watertight test errs in proportion to the
  // vertices' magnitude: the classic source of acne on big ground planes).
  const std::string ground = "p 4\n5000 5000 -2\n-5000 5000 -2\n-5000 -5000 -2\n5000 -5000 -2\n";
  for (const std::string& geometry : {std::string("s 0 0 0 2\n"), IcosphereNFF(), ground}) {
    Scene scene;
    ParseNFF(std::string(kView) + geometry, "convex", scene);
    RenderOptions ro;
    RenderStats st;
    test::RenderWith(scene, Backend::Scalar, AccelKind::BVH, ro, &st);
    INFO(scene.NumPrims(), " primitives: ", st.shadowRays, " shadow rays");
    CHECK(st.shadowRays > 3000u);
    CHECK(st.shadowHits == 0u);  // every shadow ray starts where N.L > 0
    CHECK(st.selfShadowed == 0u);
  }
}

TEST_CASE("a huge ground (a sphere of radius 1e6, a quad 2e6 across) neither shadows itself nor loses contact shadows")
{
  // A unit sphere resting on the ground, lit from straight above: the ground
  // point under it is in its shadow. The float offset bound of a primitive
  // 1e6 in size (SurfacePoint::error, 4 units here) would start that shadow
  // ray above the sphere; robust tracers need only a few ulps of the point.
  const char* view = "b 0 0 0\nv\nfrom 0 6 12\nat 0 0.5 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 64 64\n"
                     "l 0 100 0\nf 0.8 0.8 0.8 1 0 1 0 0\n";
  const std::string grounds[] = {"s 0 -1000000 0 1000000\n",
                                 "p 4\n-1000000 0 -1000000\n-1000000 0 1000000\n1000000 0 1000000\n1000000 0 -1000000\n"};
  for (const std::string& ground : grounds) {
    for (Backend backend : {Backend::Scalar, Backend::Simd}) {
      Scene scene;
      ParseNFF(std::string(view) + ground + "s 0 1 0 1\n", "ground", scene);
      RenderOptions ro;
      RenderStats st;
      test::RenderWith(scene, backend, AccelKind::BVH, ro, &st);
      INFO(ground, " ", BackendName(backend), ": ", st.shadowRays, " shadow rays, ", st.shadowHits, " blocked");
      CHECK(st.selfShadowed == 0u);
      // Only the ground near the sphere's foot can be blocked (the sphere's
      // upper half sees the light, its lower half casts no shadow ray): with
      // the float bound every ground shadow ray would start above the sphere
      // and none would be blocked.
      CHECK(st.shadowHits > 10u);
    }
  }
}

TEST_CASE("images agree across structures and backends (PSNR >= 60 dB) and with the reference")
{
  const AccelKind accels[] = {AccelKind::BVH};
  for (const std::string& name : test::Scenes({"balls", "gears", "mount", "rings", "teapot", "tetra", "tree"})) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    RenderOptions ro;
    ro.spd = true;  // corner rays averaged, as the acceptance renders are
    ro.width = ro.height = 160;
    Image ref = test::RenderWith(scene, Backend::Reference, AccelKind::BVH, ro, nullptr);
    for (AccelKind accel : accels) {
      Image img = test::RenderWith(scene, Backend::Scalar, accel, ro, nullptr);
      ImageDiff d = CompareImages(img.width, img.height, img.rgb, ref.rgb);
      INFO(std::string(name), " ", std::string(AccelKindName(accel)), ": PSNR ", d.psnr, " dB, ", d.nDiffering, " pixels differ");
      CHECK(d.psnr >= 60.0);
    }
  }
}
