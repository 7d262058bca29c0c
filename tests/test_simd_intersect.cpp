// The SIMD intersectors lane by lane against the scalar kernels, on named
// hard inputs (Embree's verify style): direction components of +0 and -0,
// origins on slab planes, rays exactly along an edge shared by two triangles
// and through a shared vertex, tangent rays to spheres and cylinders, rays
// parallel to a cone's generator (its linear case), degenerate cones; then
// seeded random rays around each primitive. Both forms are probed: the packet
// form (N rays against one primitive) and the single-ray form (one ray
// against a pack of K primitives). Answers must agree bit for bit.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include <doctest/doctest.h>
#include <fmt/format.h>

#include "host/scalar/scalar_kernels.h"
#include "host/scene/scene.h"
#include "simd/probe_scene.h"
#include "simd/isa.h"
#include "simd/simd_kernels.h"

using namespace cr;
using simd::KernelProbes;
using simd::ProbeResult;

namespace {

RayRecord MakeRay(float ox, float oy, float oz, float dx, float dy, float dz, float tmin = 0.0f, float tmax = INFINITY)
{
  return RayRecord{{ox, oy, oz}, tmin, {dx, dy, dz}, tmax};
}

std::uint32_t Bits(float x)
{
  std::uint32_t b;
  std::memcpy(&b, &x, 4);
  return b;
}

// The test scene: two triangles sharing the diagonal of the unit square,
// spheres, cylinders and cones, including degenerate ones.
struct TestScene : simd::ProbeScene {
  TestScene()
  {
    scene.spheres.push_back(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f});
    scene.spheres.push_back(Sphere{{3.0f, 0.5f, -2.0f}, 0.25f});
    scene.spheres.push_back(Sphere{{1000.0f, 2000.0f, 1.0e5f}, 1000.0f});  // far, large
    scene.spheres.push_back(Sphere{{0.5f, 0.5f, 0.5f}, 0.0f});             // radius 0
    scene.spheres.push_back(Sphere{{0.1f, -0.3f, 0.7f}, 0.7f});            // radii whose squares round
    scene.spheres.push_back(Sphere{{-0.6f, 0.2f, -0.1f}, 1.3f});
    scene.spheres.push_back(Sphere{{0.3f, 0.3f, 0.3f}, 0.123456f});
    scene.triangles.push_back(Triangle{{0.0f, 0.0f, 0.0f}, 0u, {1.0f, 0.0f, 0.0f}, 0u, {1.0f, 1.0f, 0.0f}, 0u});
    scene.triangles.push_back(Triangle{{0.0f, 0.0f, 0.0f}, 0u, {1.0f, 1.0f, 0.0f}, 0u, {0.0f, 1.0f, 0.0f}, 0u});
    scene.triangles.push_back(Triangle{{0.2f, 0.3f, 0.7f}, 0u, {0.9f, 0.1f, 0.4f}, 0u, {0.4f, 0.8f, 0.1f}, 0u});
    scene.triangles.push_back(Triangle{{0.0f, 0.0f, 0.0f}, 0u, {1.0f, 1.0f, 1.0f}, 0u, {2.0f, 2.0f, 2.0f}, 0u});
    scene.cones.push_back(Cone{{0.0f, 0.0f, 0.0f}, 1.0f, {0.0f, 0.0f, 2.0f}, 1.0f});   // cylinder
    scene.cones.push_back(Cone{{0.0f, 0.0f, 0.0f}, 1.0f, {0.0f, 0.0f, 1.0f}, 0.0f});   // cone to a point
    scene.cones.push_back(Cone{{1.0f, 2.0f, 3.0f}, 0.5f, {2.0f, 1.0f, 5.0f}, 0.25f});  // oblique frustum
    scene.cones.push_back(Cone{{1.0f, 1.0f, 1.0f}, 0.5f, {1.0f, 1.0f, 1.0f}, 0.5f});   // H = 0
    scene.boxes.push_back(Box{{-1.0f, -1.0f, -1.0f}, 0u, {1.0f, 1.0f, 1.0f}, 0u});      // the unit cube
    scene.boxes.push_back(Box{{0.25f, -0.5f, 0.1f}, 0u, {0.75f, 0.5f, 0.1f}, 0u});      // flat on z
    scene.boxes.push_back(Box{{1e4f, 2e4f, -3e4f}, 0u, {1.5e4f, 2.0001e4f, -2.9e4f}, 0u});  // far, thin
    Finish();
  }
};

// Prim_Intersect of the scalar kernels (the scalar backend's robust or fast
// instance) from a fresh hit at the ray's tmax.
ProbeResult ScalarPrim(const simd::ProbeScene& ps, const RayRecord& rec, std::uint32_t g, bool fast)
{
  KernelArgs a;
#define CR_TEST_ARGS_ARRAY_(T, U, array) a.array = ps.scene.array.data();
  CR_PRIM_TYPES(CR_TEST_ARGS_ARRAY_)
#undef CR_TEST_ARGS_ARRAY_
  a.ranges = ps.sc.ranges;
  ProbeResult out;
  out.hit = fast ? k_fast::IntersectPiece(a, g, rec, &out.t, &out.u, &out.v)
                 : k_robust::IntersectPiece(a, g, rec, &out.t, &out.u, &out.v);
  return out;
}

ProbeResult ScalarBox(const float lo[3], const float hi[3], const RayRecord& rec, bool fast)
{
  ProbeResult out;
  out.hit = fast ? k_fast::IntersectBounds(lo, hi, rec, &out.t) : k_robust::IntersectBounds(lo, hi, rec, &out.t);
  return out;
}

struct Tally {
  std::uint64_t lanes = 0, hits = 0, mismatches = 0;
};

void Compare(const ProbeResult& want, const ProbeResult& got, bool compareUV, Tally& tally, const char* what,
             const RayRecord& r, std::uint32_t g)
{
  ++tally.lanes;
  tally.hits += want.hit ? 1 : 0;
  bool same = (want.hit != 0) == (got.hit != 0);
  if (same && want.hit) {
    same = Bits(want.t) == Bits(got.t);
    if (compareUV) same = same && Bits(want.u) == Bits(got.u) && Bits(want.v) == Bits(got.v);
  }
  if (!same) {
    ++tally.mismatches;
    if (tally.mismatches <= 5)
      MESSAGE(
          fmt::format("{} g={} org=({:a},{:a},{:a}) dir=({:a},{:a},{:a}): scalar hit={} t={:a} u={:a} v={:a}; "
                      "simd hit={} t={:a} u={:a} v={:a}",
                      what, g, r.org[0], r.org[1], r.org[2], r.dir[0], r.dir[1], r.dir[2], want.hit, want.t, want.u,
                      want.v, got.hit, got.t, got.u, got.v));
  }
}

// Every ray against primitives [gBegin, gEnd) in both forms.
Tally ProbePrims(const KernelProbes& pr, const simd::ProbeScene& ps, const std::vector<RayRecord>& rays, std::uint32_t gBegin,
                 std::uint32_t gEnd, bool fast)
{
  Tally tally;
  const bool uv = Prim_Is(&ps.sc.ranges, CR_PRIM_TRIANGLE, gBegin);
  // Packet form: N rays per call, the last ray repeated to fill the packet.
  std::vector<ProbeResult> out(std::size_t(pr.width));
  for (std::uint32_t g = gBegin; g < gEnd; ++g) {
    for (std::size_t i = 0; i < rays.size(); i += std::size_t(pr.width)) {
      std::vector<RayRecord> lanes(std::size_t(pr.width));
      for (int l = 0; l < pr.width; ++l) lanes[std::size_t(l)] = rays[std::min(i + std::size_t(l), rays.size() - 1)];
      pr.packetPrim(ps.sc, lanes.data(), g, fast, out.data());
      for (int l = 0; l < pr.width && i + std::size_t(l) < rays.size(); ++l)
        Compare(ScalarPrim(ps, lanes[std::size_t(l)], g, fast), out[std::size_t(l)], uv, tally, "packet",
                lanes[std::size_t(l)], g);
    }
  }
  // Single-ray form: the primitives in packs of K, CR_NO_HIT padding.
  std::vector<ProbeResult> pout(std::size_t(pr.packWidth));
  for (const RayRecord& r : rays) {
    for (std::uint32_t g0 = gBegin; g0 < gEnd; g0 += std::uint32_t(pr.packWidth)) {
      std::vector<std::uint32_t> gs(std::size_t(pr.packWidth), CR_NO_HIT);
      for (int l = 0; l < pr.packWidth && g0 + std::uint32_t(l) < gEnd; ++l) gs[std::size_t(l)] = g0 + std::uint32_t(l);
      pr.singlePrims(ps.sc, r, gs.data(), fast, pout.data());
      for (int l = 0; l < pr.packWidth; ++l) {
        if (gs[std::size_t(l)] == CR_NO_HIT) {
          CHECK(pout[std::size_t(l)].hit == 0);  // padding never hits
          continue;
        }
        Compare(ScalarPrim(ps, r, gs[std::size_t(l)], fast), pout[std::size_t(l)], uv, tally, "single", r,
                gs[std::size_t(l)]);
      }
    }
  }
  return tally;
}

std::vector<KernelProbes> AvailableProbes()
{
  std::vector<KernelProbes> out;
  for (const std::string& isa : simd::SupportedVectorIsas()) out.push_back(simd::IsaProbes(simd::ParseIsa(isa)));
  if (out.empty()) MESSAGE("SKIPPED: no SIMD ISA on this CPU");
  return out;
}

// Seeded random rays aimed at points of a box, from all around it.
std::vector<RayRecord> RaysAround(float cx, float cy, float cz, float size, int n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<RayRecord> rays;
  for (int i = 0; i < n; ++i) {
    const float tx = cx + size * u(rng), ty = cy + size * u(rng), tz = cz + size * u(rng);
    const float ox = cx + 4.0f * size * u(rng), oy = cy + 4.0f * size * u(rng), oz = cz + 4.0f * size * u(rng);
    rays.push_back(MakeRay(ox, oy, oz, tx - ox, ty - oy, tz - oz));
  }
  return rays;
}

}  // namespace

TEST_CASE("simd intersectors: shared triangle edge and vertex, signed-zero directions (watertight)")
{
  TestScene ps;
  const std::uint32_t t0 = Prim_Count(&ps.sc.ranges, CR_PRIM_SPHERE), tEnd = t0 + Prim_Count(&ps.sc.ranges, CR_PRIM_TRIANGLE);
  std::vector<RayRecord> rays;
  // Straight down onto the shared diagonal x = y and the shared vertices,
  // with every sign of zero in the lateral components.
  for (float p : {0.0f, 0.1f, 0.25f, 0.5f, 0.75f, 1.0f}) {
    for (float zx : {0.0f, -0.0f})
      for (float zy : {0.0f, -0.0f}) {
        rays.push_back(MakeRay(p, p, 1.0f, zx, zy, -1.0f));
        rays.push_back(MakeRay(p, p, -1.0f, zx, zy, 1.0f));
        rays.push_back(MakeRay(p, 1.0f, 1.0f, zx, zy, -1.0f));  // outer edge y = 1
      }
  }
  // Oblique rays through points of the diagonal, and a ray lying in the plane.
  for (float p : {0.125f, 0.5f, 0.875f}) {
    rays.push_back(MakeRay(p + 0.3f, p - 0.2f, 1.0f, -0.3f, 0.2f, -1.0f));
    rays.push_back(MakeRay(p - 0.5f, p + 0.5f, 0.5f, 0.5f, -0.5f, -0.5f));
  }
  rays.push_back(MakeRay(-1.0f, -1.0f, 0.0f, 1.0f, 1.0f, 0.0f));
  rays.push_back(MakeRay(-1.0f, -1.0f, 0.0f, 1.0f, 1.0f, -0.0f));
  for (const KernelProbes& pr : AvailableProbes()) {
    for (bool fast : {false, true}) {
      const Tally t = ProbePrims(pr, ps, rays, t0, tEnd, fast);
      INFO("width ", pr.width, fast ? " fast" : " robust");
      CHECK(t.mismatches == 0);
      CHECK(t.hits > 0);
    }
    // Watertight: a ray straight down onto the shared diagonal hits at least
    // one of the two triangles (robust mode), in the SIMD kernels too.
    for (float p : {0.1f, 0.25f, 0.5f, 0.75f}) {
      std::vector<RayRecord> lanes(std::size_t(pr.width), MakeRay(p, p, 1.0f, -0.0f, 0.0f, -1.0f));
      std::vector<ProbeResult> a(std::size_t(pr.width)), b(std::size_t(pr.width));
      pr.packetPrim(ps.sc, lanes.data(), t0, false, a.data());
      pr.packetPrim(ps.sc, lanes.data(), t0 + 1, false, b.data());
      CHECK((a[0].hit || b[0].hit));
      CHECK(a[0].t == doctest::Approx(1.0f));
    }
  }
}

TEST_CASE("simd intersectors: tangent and grazing rays to spheres")
{
  TestScene ps;
  const float up = std::nextafter(1.0f, 2.0f), down = std::nextafter(1.0f, 0.0f);
  std::vector<RayRecord> rays;
  for (float y : {1.0f, up, down, -1.0f, 0.0f})
    for (float z0 : {0.0f, -0.0f}) {
      rays.push_back(MakeRay(-5.0f, y, 0.0f, 1.0f, z0, z0));  // tangent when |y| = 1 (discriminant exactly 0)
      rays.push_back(MakeRay(0.0f, y, -5.0f, z0, 0.0f, 1.0f));
    }
  rays.push_back(MakeRay(0.0f, 0.0f, 0.0f, 0.3f, 0.4f, 0.5f));                // from the centre
  rays.push_back(MakeRay(-1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f));               // from the surface
  rays.push_back(MakeRay(-1.0f, 0.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.0f, 5.0f));  // leaving it
  rays.push_back(MakeRay(0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f));                // zero direction
  rays.push_back(MakeRay(1000.0f, 3000.0f, 0.0f, 0.0f, -0.0f, 1.0f));         // tangent to the far sphere
  rays.push_back(MakeRay(3.0f, 0.75f, -10.0f, 0.0f, 0.0f, 1.0f));             // tangent to sphere 1
  for (const KernelProbes& pr : AvailableProbes()) {
    for (bool fast : {false, true}) {
      const Tally t = ProbePrims(pr, ps, rays, 0, Prim_Count(&ps.sc.ranges, CR_PRIM_SPHERE), fast);
      INFO("width ", pr.width, fast ? " fast" : " robust");
      CHECK(t.mismatches == 0);
      CHECK(t.hits > 0);
    }
  }
}

TEST_CASE("simd intersectors: cylinders and cones, the linear case and degenerate cones")
{
  TestScene ps;
  const std::uint32_t c0 = ps.sc.ranges.begin[CR_PRIM_CONE], cEnd = c0 + Prim_Count(&ps.sc.ranges, CR_PRIM_CONE);
  std::vector<RayRecord> rays;
  for (float z0 : {0.0f, -0.0f}) {
    rays.push_back(MakeRay(-5.0f, 1.0f, 1.0f, 1.0f, z0, z0));     // tangent to the cylinder
    rays.push_back(MakeRay(-5.0f, 0.5f, 1.0f, 1.0f, z0, z0));     // through it
    rays.push_back(MakeRay(0.5f, 0.0f, -3.0f, z0, z0, 1.0f));     // parallel to the axis (A = 0, Bh = 0)
    rays.push_back(MakeRay(2.0f, 0.0f, -1.0f, -1.0f, z0, 1.0f));  // parallel to the cone's generator (A = 0)
    rays.push_back(MakeRay(2.0f, 0.5f, -1.0f, -1.0f, z0, 1.0f));
    rays.push_back(MakeRay(1.0f, 1.0f, 0.0f, z0, z0, 1.0f));  // along the degenerate cone's axis
  }
  rays.push_back(MakeRay(0.0f, 0.0f, 1.0f, 1.0f, 0.0f, 0.0f));  // from inside
  for (const KernelProbes& pr : AvailableProbes()) {
    for (bool fast : {false, true}) {
      const Tally t = ProbePrims(pr, ps, rays, c0, cEnd, fast);
      INFO("width ", pr.width, fast ? " fast" : " robust");
      CHECK(t.mismatches == 0);
      CHECK(t.hits > 0);
    }
  }
}

TEST_CASE("simd intersectors: seeded random rays around every primitive")
{
  TestScene ps;
  const PrimRanges c = ps.sc.ranges;
  struct Group {
    std::uint32_t begin, end;
    float cx, cy, cz, size;
  };
  const Group groups[] = {{c.begin[CR_PRIM_SPHERE], c.begin[CR_PRIM_TRIANGLE], 0.0f, 0.0f, 0.0f, 1.2f},
                          {c.begin[CR_PRIM_TRIANGLE], c.begin[CR_PRIM_CONE], 0.5f, 0.5f, 0.3f, 0.8f},
                          {c.begin[CR_PRIM_CONE], c.begin[CR_PRIM_BOX], 0.5f, 0.5f, 1.5f, 2.0f},
                          {c.begin[CR_PRIM_BOX], c.begin[CR_NUM_PRIM_TYPES], 0.0f, 0.0f, 0.0f, 1.5f}};
  unsigned seed = 1;
  for (const KernelProbes& pr : AvailableProbes()) {
    for (const Group& gr : groups) {
      const auto rays = RaysAround(gr.cx, gr.cy, gr.cz, gr.size, 400, seed++);
      for (bool fast : {false, true}) {
        const Tally t = ProbePrims(pr, ps, rays, gr.begin, gr.end, fast);
        INFO("width ", pr.width, " group ", gr.begin, fast ? " fast" : " robust");
        CHECK(t.mismatches == 0);
        CHECK(t.hits > 20);
      }
    }
  }
}

TEST_CASE("simd intersectors: slab tests with zero directions, origins on planes and flat boxes")
{
  const float boxes[][6] = {{0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f},
                            {0.0f, 0.0f, 0.5f, 1.0f, 1.0f, 0.5f},  // flat in z
                            {-2.0f, -1.0f, -3.0f, 4.0f, 0.0f, -1.0f},
                            {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY}};  // empty
  std::vector<RayRecord> rays;
  for (float z0 : {0.0f, -0.0f}) {
    rays.push_back(MakeRay(0.0f, 0.5f, 0.5f, z0, z0, 1.0f));   // origin on the plane x = 0, parallel to it
    rays.push_back(MakeRay(1.0f, 0.5f, -2.0f, z0, z0, 1.0f));  // on the plane x = 1
    rays.push_back(MakeRay(0.5f, 0.5f, -2.0f, z0, z0, 1.0f));
    rays.push_back(MakeRay(0.5f, 0.5f, 2.0f, z0, z0, -1.0f));
    rays.push_back(MakeRay(0.5f, 0.5f, 0.5f, 1.0f, z0, z0));   // from inside, in the flat box's plane
    rays.push_back(MakeRay(-1.0f, 1.0f, 0.5f, 1.0f, z0, z0));  // grazing the face y = 1
    rays.push_back(MakeRay(-1.0f, -1.0f, -1.0f, 1.0f, 1.0f, 1.0f, 0.0f, 1.0f));
    rays.push_back(MakeRay(0.0f, 0.0f, 0.0f, z0, z0, z0));  // zero direction at a corner
  }
  const auto random = RaysAround(0.5f, 0.5f, 0.5f, 1.0f, 200, 99);
  rays.insert(rays.end(), random.begin(), random.end());
  for (const KernelProbes& pr : AvailableProbes()) {
    for (bool fast : {false, true}) {
      Tally tally;
      for (const auto& b : boxes) {
        const float lo[3] = {b[0], b[1], b[2]}, hi[3] = {b[3], b[4], b[5]};
        // Packet form.
        std::vector<ProbeResult> out(std::size_t(pr.width));
        for (std::size_t i = 0; i < rays.size(); i += std::size_t(pr.width)) {
          std::vector<RayRecord> lanes(std::size_t(pr.width));
          for (int l = 0; l < pr.width; ++l)
            lanes[std::size_t(l)] = rays[std::min(i + std::size_t(l), rays.size() - 1)];
          pr.packetBox(lo, hi, lanes.data(), fast, out.data());
          for (int l = 0; l < pr.width && i + std::size_t(l) < rays.size(); ++l)
            Compare(ScalarBox(lo, hi, lanes[std::size_t(l)], fast), out[std::size_t(l)], false, tally, "packet box",
                    lanes[std::size_t(l)], 0);
        }
        // Packet form with one ray in every lane (the packet's same-signs path).
        for (const RayRecord& r : rays) {
          std::vector<RayRecord> lanes(std::size_t(pr.width), r);
          pr.packetBox(lo, hi, lanes.data(), fast, out.data());
          const ProbeResult want = ScalarBox(lo, hi, r, fast);
          for (int l = 0; l < pr.width; ++l) Compare(want, out[std::size_t(l)], false, tally, "uniform box", r, 0);
        }
        // Single-ray form: the box in every child slot of one node.
        std::vector<float> los(std::size_t(3 * pr.width)), his(std::size_t(3 * pr.width));
        for (int a = 0; a < 3; ++a)
          for (int l = 0; l < pr.width; ++l) {
            los[std::size_t(a * pr.width + l)] = lo[a];
            his[std::size_t(a * pr.width + l)] = hi[a];
          }
        for (const RayRecord& r : rays) {
          pr.singleBoxes(los.data(), his.data(), r, fast, out.data());
          const ProbeResult want = ScalarBox(lo, hi, r, fast);
          for (int l = 0; l < pr.width; ++l) Compare(want, out[std::size_t(l)], false, tally, "node box", r, 0);
        }
      }
      INFO("width ", pr.width, fast ? " fast" : " robust");
      CHECK(tally.mismatches == 0);
      CHECK(tally.hits > 0);
    }
  }
}

namespace {

// Rays that leave surfaces, as secondary rays do: origins on a tree's
// joints (a cone and the next one meeting at a sphere), on a ground sphere
// of radius 1e6, on a fan of coplanar triangles and on a thin cylinder far
// from the world origin, each moved off its surface by the ray generator's
// error bound (host/scene/surface.h: 2^-19 S + 2^-22 |p|) to either side,
// and by smaller offsets (the renderer's, and below), with directions
// over the hemisphere it faces, to a point light (tmax 1)
// or unbounded, and a quarter of them back through the surface. These are
// the rays whose roots robust mode decides in
// windows (Sphere_NeedsDf, Cone_NeedsDf, Triangle_PlaneNeedsDf), and that a
// window too narrow gets wrong.
struct SurfaceScene : simd::ProbeScene {
  SurfaceScene()
  {
    scene.spheres.push_back(Sphere{{0.0f, 0.0f, 1.0f}, 0.1005f});
    scene.spheres.push_back(Sphere{{0.417812f, 0.0f, 1.49793f}, 0.067335f});
    scene.spheres.push_back(Sphere{{0.0f, -1.0e6f, 0.0f}, 999990.0f});
    for (int i = 0; i < 4; ++i) {  // a fan around (0.3, 0.2, -0.4) in one tilted plane
      const double a0 = i * 1.5707963267948966, a1 = a0 + 1.5707963267948966;
      auto P = [](double a) {
        return std::array<float, 3>{float(0.3 + 0.5 * std::cos(a)), float(0.2 + 0.5 * std::sin(a)),
                                    float(-0.4 + 0.25 * std::cos(a) + 0.1 * std::sin(a))};
      };
      const auto p = P(a0), q = P(a1);
      scene.triangles.push_back(Triangle{{0.3f, 0.2f, -0.4f}, 0u, {p[0], p[1], p[2]}, 0u, {q[0], q[1], q[2]}, 0u});
    }
    scene.cones.push_back(Cone{{0.0f, 0.0f, 0.0f}, 0.15f, {0.0f, 0.0f, 1.0f}, 0.1005f});
    scene.cones.push_back(Cone{{0.0f, 0.0f, 1.0f}, 0.1005f, {0.417812f, 0.0f, 1.49793f}, 0.067335f});
    scene.cones.push_back(Cone{{0.417812f, 0.0f, 1.49793f}, 0.067335f, {0.625853f, 0.271578f, 1.74586f}, 0.0451145f});
    scene.cones.push_back(Cone{{1000.0f, 2000.0f, 3000.0f}, 0.5f, {1003.0f, 2004.0f, 3012.0f}, 0.5f});  // far cylinder
    Finish();
  }
};

struct SurfacePoint3 {
  double p[3], n[3];
};

// A point of primitive g's surface (in double) with its unit normal.
SurfacePoint3 PointOn(const Scene& s, const PrimRanges& c, std::uint32_t g, std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(0.0, 1.0);
  SurfacePoint3 out{};
  if (Prim_Is(&c, CR_PRIM_SPHERE, g)) {
    const Sphere& sp = s.spheres[Prim_Local(&c, CR_PRIM_SPHERE, g)];
    const double z = 2.0 * u(rng) - 1.0, ph = 6.283185307179586 * u(rng), r = std::sqrt(1.0 - z * z);
    double n[3] = {r * std::cos(ph), r * std::sin(ph), z};
    if (sp.radius > 1e5f) n[0] *= 1e-5, n[1] = 1.0, n[2] *= 1e-5;  // the top of the ground sphere
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; ++i) out.n[i] = n[i] / l, out.p[i] = sp.center[i] + double(sp.radius) * out.n[i];
  } else if (Prim_Is(&c, CR_PRIM_TRIANGLE, g)) {
    const Triangle& t = s.triangles[Prim_Local(&c, CR_PRIM_TRIANGLE, g)];
    double a = u(rng), b = u(rng);
    if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
    double e1[3], e2[3];
    for (int i = 0; i < 3; ++i) {
      e1[i] = double(t.v1[i]) - t.v0[i], e2[i] = double(t.v2[i]) - t.v0[i];
      out.p[i] = t.v0[i] + a * e1[i] + b * e2[i];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; ++i) out.n[i] = n[i] / l;
  } else {
    const Cone& cn = s.cones[Prim_Local(&c, CR_PRIM_CONE, g)];
    double w[3], H = 0.0;
    for (int i = 0; i < 3; ++i) w[i] = double(cn.apex[i]) - cn.base[i], H += w[i] * w[i];
    H = std::sqrt(H);
    for (double& x : w) x /= H;
    const double a2[3] = {std::fabs(w[0]) > 0.6 ? 0.0 : 1.0, std::fabs(w[0]) > 0.6 ? 1.0 : 0.0, 0.0};
    double e[3] = {w[1] * a2[2] - w[2] * a2[1], w[2] * a2[0] - w[0] * a2[2], w[0] * a2[1] - w[1] * a2[0]};
    const double el = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (double& x : e) x /= el;
    const double f[3] = {w[1] * e[2] - w[2] * e[1], w[2] * e[0] - w[0] * e[2], w[0] * e[1] - w[1] * e[0]};
    const double k = (double(cn.apexRadius) - cn.baseRadius) / H, sAx = H * u(rng), ph = 6.283185307179586 * u(rng);
    const double rs = cn.baseRadius + k * sAx;
    double n[3], nl = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double radial = std::cos(ph) * e[i] + std::sin(ph) * f[i];
      out.p[i] = cn.base[i] + sAx * w[i] + rs * radial;
      n[i] = radial - k * w[i];
      nl += n[i] * n[i];
    }
    for (int i = 0; i < 3; ++i) out.n[i] = n[i] / std::sqrt(nl);
  }
  return out;
}

// Rays leaving each primitive of the scene, n per primitive.
std::vector<RayRecord> RaysLeaving(const simd::ProbeScene& ps, int n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<RayRecord> rays;
  const PrimRanges& c = ps.sc.ranges;
  for (std::uint32_t g = 0; g < c.begin[CR_NUM_PRIM_TYPES]; ++g) {
    for (int i = 0; i < n; ++i) {
      const SurfacePoint3 sp = PointOn(ps.scene, c, g, rng);
      double S = 0.0, pm = 0.0;  // the primitive's scale (its bounds) and |p|
      const Bounds b = ps.scene.UnifiedBounds(g);
      for (int a = 0; a < 3; ++a) S = std::max({S, std::fabs(double(b.lo[a])), std::fabs(double(b.hi[a]))});
      for (double x : sp.p) pm = std::max(pm, std::fabs(x));
      // Offsets: the ray generator's bound, the renderer's robust offset
      // (2^-21 |p| + 2^-40 S) and smaller ones, down to where only the exact
      // cold path tells the sides apart.
      const int kind = (i / 4) % 3;
      const double side = (i & 1) ? 1.0 : -1.0;
      const double off = kind == 0   ? std::ldexp(S, -19) + std::ldexp(pm, -22)
                         : kind == 1 ? std::ldexp(pm, -21) + std::ldexp(S, -40)
                                     : std::ldexp(S, -22 - int(10.0 * (0.5 + 0.5 * u(rng))));
      double d[3], dn = 0.0;
      for (int a = 0; a < 3; ++a) d[a] = u(rng), dn += d[a] * sp.n[a];
      // Away from the side it sits on, or (one in four) back through the
      // surface it sits 2^-19 S above, as a refracted or a badly offset ray.
      const bool through = (i & 3) == 3;
      if ((dn * side < 0.0) != through)
        for (double& x : d) x = -x;
      const bool toLight = (i & 2) != 0;
      const double len = toLight ? 10.0 * S + 1.0 : 1.0;
      rays.push_back(MakeRay(float(sp.p[0] + side * off * sp.n[0]), float(sp.p[1] + side * off * sp.n[1]),
                             float(sp.p[2] + side * off * sp.n[2]), float(len * d[0]), float(len * d[1]),
                             float(len * d[2]), 0.0f, toLight ? 1.0f : INFINITY));
    }
  }
  return rays;
}

}  // namespace

TEST_CASE("robust intersectors: rays leaving surfaces agree with fp64, and SIMD with scalar bit for bit")
{
  SurfaceScene ps;
  const PrimRanges c = ps.sc.ranges;
  const auto rays = RaysLeaving(ps, 300, 7);
  KernelArgs a;
#define CR_TEST_ARGS_ARRAY_(T, U, array) a.array = ps.scene.array.data();
  CR_PRIM_TYPES(CR_TEST_ARGS_ARRAY_)
#undef CR_TEST_ARGS_ARRAY_
  a.ranges = c;
  // Every ray against every primitive, robust against fp64: the same hit or
  // miss, and t within a few ulps of the ray's scale (the origins sit 2^-19
  // of the primitive's scale off the surface, far outside any window, so
  // nothing here is marginal).
  std::uint64_t hits = 0, flips = 0, far = 0, anyFlips = 0;
  for (const RayRecord& r : rays) {
    const double scale = std::max({std::fabs(r.org[0]), std::fabs(r.org[1]), std::fabs(r.org[2])}) /
                         std::max({std::fabs(r.dir[0]), std::fabs(r.dir[1]), std::fabs(r.dir[2])});
    for (std::uint32_t g = 0; g < c.begin[CR_NUM_PRIM_TYPES]; ++g) {
      ProbeResult rb, fp;
      rb.hit = k_robust::IntersectPiece(a, g, r, &rb.t, &rb.u, &rb.v);
      fp.hit = k_fp64::IntersectPiece(a, g, r, &fp.t, &fp.u, &fp.v);
      // The any-hit query (which may keep a float hit certainly in range)
      // finds the same hit or miss.
      ProbeResult any;
      any.hit = k_robust::IntersectPiece(a, g, r, &any.t, &any.u, &any.v, true);
      anyFlips += (any.hit != 0) != (fp.hit != 0) ? 1 : 0;
      if (rb.hit != fp.hit) {
        if (++flips <= 5)
          MESSAGE(fmt::format("g={} org=({:a},{:a},{:a}) dir=({:a},{:a},{:a}) tmax={}: robust hit={} t={} fp64 hit={} t={}",
                              g, r.org[0], r.org[1], r.org[2], r.dir[0], r.dir[1], r.dir[2], r.tmax, rb.hit, rb.t,
                              fp.hit, fp.t));
        continue;
      }
      if (!rb.hit) continue;
      ++hits;
      if (std::fabs(double(rb.t) - fp.t) > 0x1.0p-20 * (scale + fp.t)) ++far;
    }
  }
  CHECK(flips == 0);
  CHECK(anyFlips == 0);
  CHECK(far == 0);
  CHECK(hits > 400);
  unsigned seed = 11;
  for (const KernelProbes& pr : AvailableProbes()) {
    for (unsigned type = 0; type < CR_NUM_PRIM_TYPES; ++type) {
      if (c.begin[type] == c.begin[type + 1]) continue;
      const Tally t = ProbePrims(pr, ps, RaysLeaving(ps, 60, seed++), c.begin[type], c.begin[type + 1], false);
      INFO("width ", pr.width, " type ", type);
      CHECK(t.mismatches == 0);
      CHECK(t.hits > 10);
    }
  }
}
