// The BVH builder's spatial splits (--bvh-quality high, SBVH): references
// cut by planes still cover their primitives, and every backend answers as
// with the object-split BVH.
#include <cstring>

#include <doctest/doctest.h>
#include <fmt/format.h>

#include "host/accel/accel.h"
#include "host/core/error.h"
#include "host/trace/tracer.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

AccelParams High()
{
  AccelParams p;
  p.bvhQuality = "high";
  return p;
}

bool Inside(const BVHNode& b, const glm::dvec3& p)
{
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= b.bmin[a] && p[a] <= b.bmax[a])) return false;
  return true;
}

}  // namespace

TEST_CASE("bvh: spatial splits cut references, which still cover their triangles, within the budget")
{
  for (const std::string& name : test::Scenes({"gears", "tree", "balls"})) {
    CAPTURE(name);
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    AccelInfo mi, hi;
    const BVHData m = BuildBVH(scene, AccelParams{}, mi);
    const BVHData h = BuildBVH(scene, High(), hi);
    const std::uint32_t n = scene.NumUnified();
    CHECK(m.refs.size() == n);
    CHECK(h.refs.size() >= n);
    CHECK(h.refs.size() <= n + std::size_t(0.3 * n) + 1);  // the budget
    CHECK(hi.params.find("quality=high") != std::string::npos);
    // Leaves: ids ascending (grouped by type), none twice; every leaf of g.
    std::vector<std::vector<std::uint32_t>> leavesOf(n);
    for (std::uint32_t i = 0; i < h.nodes.size(); ++i) {
      const BVHNode& b = h.nodes[i];
      if (b.count == 0) {
        // Interior: the children's boxes lie within.
        for (std::uint32_t c = b.first; c < b.first + 2; ++c)
          for (int a = 0; a < 3; ++a) {
            CHECK(h.nodes[c].bmin[a] >= b.bmin[a]);
            CHECK(h.nodes[c].bmax[a] <= b.bmax[a]);
          }
        continue;
      }
      for (std::uint32_t k = b.first; k < b.first + b.count; ++k) {
        if (k > b.first) CHECK(h.refs[k - 1] < h.refs[k]);
        REQUIRE(h.refs[k] < n);
        leavesOf[h.refs[k]].push_back(i);
      }
    }
    // Every point of every triangle (a barycentric lattice, vertices and
    // edges included) lies in the box of a leaf that references it.
    const PrimRanges r = scene.Ranges();
    std::size_t split = 0, uncovered = 0;
    for (std::uint32_t g = 0; g < n; ++g) {
      CHECK(!leavesOf[g].empty());
      split += leavesOf[g].size() > 1;
      if (!Prim_Is(&r, CR_PRIM_TRIANGLE, g)) continue;
      const Triangle& t = scene.triangles[Prim_Local(&r, CR_PRIM_TRIANGLE, g)];
      const glm::dvec3 v0(t.v0[0], t.v0[1], t.v0[2]), v1(t.v1[0], t.v1[1], t.v1[2]), v2(t.v2[0], t.v2[1], t.v2[2]);
      constexpr int kSteps = 8;
      for (int i = 0; i <= kSteps; ++i)
        for (int j = 0; i + j <= kSteps; ++j) {
          // In double: the point itself, not a rounding of it.
          const double u = double(i) / kSteps, v = double(j) / kSteps;
          const glm::dvec3 p = (1.0 - u - v) * v0 + u * v1 + v * v2;
          bool in = false;
          for (std::uint32_t leaf : leavesOf[g]) in = in || Inside(h.nodes[leaf], p);
          if (!in && uncovered++ == 0) {
            std::string boxes;
            for (std::uint32_t leaf : leavesOf[g])
              boxes += fmt::format(" [{} {} {} .. {} {} {}]", h.nodes[leaf].bmin[0], h.nodes[leaf].bmin[1],
                                   h.nodes[leaf].bmin[2], h.nodes[leaf].bmax[0], h.nodes[leaf].bmax[1],
                                   h.nodes[leaf].bmax[2]);
            MESSAGE("uncovered: piece ", g, " point ", p.x, " ", p.y, " ", p.z, " leaves", boxes);
          }
        }
    }
    CHECK(uncovered == 0);
    MESSAGE(name << ": " << h.refs.size() - n << " extra references, " << split << " of " << n
                 << " primitives split");
    if (std::string(name) == "gears") CHECK(split > 0);
  }
}

TEST_CASE("bvh: with spatial splits every backend answers as with object splits, 0 wrong")
{
  for (const std::string& name : test::Scenes({"gears", "tree", "balls"})) {
    CAPTURE(name);
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Random}) {
      const bool occlusion = test::IsOcclusion(kind);
      const auto rays = test::MakeRays(scene, kind, 32);
      for (Backend backend : {Backend::Scalar, Backend::Simd}) {
        for (const char* variant : {"", "single"}) {
          if (backend == Backend::Scalar && *variant) continue;
          CAPTURE(int(kind));
          CAPTURE(BackendName(backend));
          CAPTURE(variant);
          TraceConfig cfg;
          cfg.backend = backend;
          cfg.variant = variant;
          std::vector<HitRecord> a, b;
          const auto ra = test::CheckTracer(scene, cfg, rays, occlusion, &a);
          cfg.params = High();
          const auto rb = test::CheckTracer(scene, cfg, rays, occlusion, &b);
          CHECK(ra.wrong == 0);
          CHECK(rb.wrong == 0);
          CHECK(test::CountDiffering(a, b, occlusion) == 0);
        }
      }
    }
  }
}

TEST_CASE("bvh: --bvh-quality takes medium or high")
{
  const Scene& scene = test::CachedScene(test::SpdPath("tetra"));
  AccelParams p;
  AccelInfo info;
  p.bvhQuality = "medium";
  CHECK(BuildBVH(scene, p, info).refs.size() == scene.NumUnified());
  p.bvhQuality = "best";
  CHECK_THROWS_AS(BuildBVH(scene, p, info), InputError);
}
