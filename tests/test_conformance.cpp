// Conformance: every structure on every CPU backend against the fp64
// reference, on every SPD scene and ray kind, at a reduced ray count
// (the full-size run is bench/conformance.sh).
#include "tests/test_util.h"

using namespace cr;

namespace {

void RunConformance(Backend backend, Precision precision, int size)
{
  for (const std::string& name : test::SpdScenes())
    test::CheckConformance(test::CachedScene(test::SpdPath(name)), name, backend, precision, size);
}

}  // namespace

TEST_CASE("conformance: scalar robust, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Robust, 48);
}

TEST_CASE("conformance: scalar fp64, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Fp64, 32);
}

// Rays leaving a 1e-4 triangle just above a ground sphere of radius 1e6
// (scenes/scale/mixed-scales.nff, two of its 2^20 diffuse rays), origins
// 6e-7 and 1.8e-6 above the sphere: |o - c|^2 and r^2 are 1e12 and cancel
// to c = 1.18. The exact roots (rational arithmetic on the float data):
// the reference, robust (its double-float cold path) and fp64 (its
// accurate c) must each find them to far better than the checker's
// tolerance, 2^-16 (|o| + t |d|) = 8e-9 here; before Sphere_CAccurate and
// the reference's SphereC they were 1.8e-8 to 2.6e-8 off, and check
// judged fp64 and robust wrong against a reference that was itself wrong.
TEST_CASE("conformance: rays leaving a surface just above a ground sphere of radius 1e6")
{
  Scene scene;
  ParseNFF("s 0 -1000000 0 1000000\n", "ground", scene);
  const std::vector<RayRecord> rays = {
      RayRecord{{0x1.acd19ap-13f, 0x1.de4890p-20f, 0x1.403a56p-12f}, 0.0f,
                {-0x1.6dcb52p-1f, -0x1.a5e0ccp-9f, -0x1.663d70p-1f}, INFINITY},
      RayRecord{{0x1.ffb41ap-13f, 0x1.3c165cp-21f, 0x1.959d50p-12f}, 0.0f,
                {-0x1.ffd72cp-1f, -0x1.0c7272p-8f, 0x1.935ef0p-6f}, INFINITY}};
  const double exact[2] = {5.5356472695426025e-4, 1.4373369186248719e-4};
  const ref::ReferenceTracer reference(scene);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const ref::RefHit h = reference.Intersect(ref::MakeRay(rays[i]));
    INFO("ray ", i);
    CHECK(h.Found());
    CHECK(std::fabs(h.t - exact[i]) < 1e-10 * exact[i]);  // the plain double form: 1.3e-4
  }
  for (Backend b : {Backend::Scalar, Backend::Simd, Backend::OpenCL})
    for (Precision p : {Precision::Robust, Precision::Fp64}) {
      if (b == Backend::Simd && p == Precision::Fp64) continue;  // the scalar kernels' (delegated)
      if (b == Backend::OpenCL && !test::HaveOpenCLDevice()) continue;
      TraceConfig cfg;
      cfg.backend = b;
      cfg.precision = p;
      std::vector<HitRecord> hits;
      CreateTracer(scene, cfg)->Trace(rays, hits, false, nullptr);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        INFO(BackendName(b), " ", PrecisionName(p), " ray ", i);
        CHECK(hits[i].prim == 0u);
        CHECK(std::fabs(double(hits[i].t) - exact[i]) < 2e-7 * exact[i]);  // a few float ulps
      }
      CHECK(ref::CheckHits(reference, rays, hits, false).wrong == 0);
    }
}
