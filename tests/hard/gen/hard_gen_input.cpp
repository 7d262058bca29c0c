// Degenerate input and extreme parameters: the loader's rules for
// degenerate statements (skipped with a warning, id kept, later ids
// unchanged), the kernels on degenerate pieces that bypass the loader, and
// structure parameters far out of range (a clear error or a clamp with a
// warning, never a crash, and right answers after a clamp).
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"
#include "host/core/error.h"

namespace cr::hard {

namespace {

// Rays from above to aim points, with the id each must report.
void AimRays(HardCase& c, const std::vector<std::pair<glm::dvec3, std::uint32_t>>& aims, std::size_t perAim,
             std::uint64_t seed)
{
  Rng rng(seed);
  for (const auto& [p, id] : aims)
    for (std::size_t k = 0; k < perAim; ++k) {
      // From above (the valid primitives lie about the plane z = 0).
      const glm::dvec3 u = glm::normalize(glm::dvec3(rng.Uniform(-0.4, 0.4), rng.Uniform(-0.4, 0.4), 1.0));
      const glm::dvec3 eye = p + rng.Uniform(6.0, 12.0) * u;
      c.rays.push_back(Rec(eye, p - eye));
      c.target.push_back(id);
    }
}

// NFF statements: valid primitives around degenerate ones. The ids a ray
// must report are the statements' positions, counted here by hand.
const char* kDegenerateNff = R"(v
from 0 0 20
at 0 0 0
up 0 1 0
angle 45
hither 0.01
resolution 64 64
s 0 0 0 1
p 3
0 0 5
1 1 5
2 2 5
p 3
1 0 5
1 0 5
2 1 5
p 4
0 5 0
1 5 0
2 5 0
3 5 0
s 4 0 0 0
c 0 8 0 1 0 8 0 1
c 0 -8 0 0 0 -8 3 0
p 2
3 3 3
4 4 4
p 6
-6 -1 0
-4 -1 0
-4 -1 0
-4 1 0
-5 1 0
-6 1 0
s 6 0 0 1
p 3
-1 -6 0
1 -6 0
0 -4 0
c 6 6 -1 0.5 6 6 1 0.25
pp 3
-6 6 0 0 0 1
-4 6 0 0 0 1
-5 8 0 0 0 1
)";

HardCase Loader(const GenOptions& o)
{
  HardCase c;
  c.name = "degenerate/loader";
  auto scene = std::make_shared<Scene>();
  const long before = WarningCount();
  ParseNFF(kDegenerateNff, "degenerate.nff", *scene);
  c.generatorWarnings = WarningCount() - before;
  c.expectGeneratorWarnings = 7;  // statements 1..7
  {
    // A backstop box after everything (ids 13..18), with the loader's rules.
    const double L = 30.0;
    auto p = [&](int x, int y, int z) { return glm::dvec3(x ? L : -L, y ? L : -L, z ? L : -L); };
    const std::vector<std::vector<glm::dvec3>> faces = {
        {p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1)}, {p(1, 0, 0), p(1, 0, 1), p(1, 1, 1), p(1, 1, 0)},
        {p(0, 0, 0), p(0, 0, 1), p(1, 0, 1), p(1, 0, 0)}, {p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1)},
        {p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0)}, {p(0, 0, 1), p(0, 1, 1), p(1, 1, 1), p(1, 0, 1)}};
    for (const auto& f : faces) AddPolygon(*scene, PrimKind::kPolygon, f, nullptr, 0, 0, "generated");
  }
  c.scene = scene;
  c.expect = Expect::Target;
  const std::uint32_t n = o.quick ? 60 : 600;
  // Valid primitives by statement id, and the places of the degenerate ones
  // (no id: the reference's answer, usually the backstop).
  AimRays(c,
          {{{0, 0, 0}, 0},
           {{-5, 0, 0}, 8},
           {{6, 0, 0}, 9},
           {{0, -5.5, 0}, 10},
           {{6.375, 6, 0}, 11},
           {{-5, 6.7, 0}, 12},
           {{1, 1, 5}, kAnyPrim},
           {{1.5, 0.5, 5}, kAnyPrim},
           {{1.5, 5, 0}, kAnyPrim},
           {{4, 0, 0}, kAnyPrim},
           {{0, 8, 0}, kAnyPrim},
           {{0, -8, 1.5}, kAnyPrim},
           {{3.5, 3.5, 3.5}, kAnyPrim}},
          n, 701);
  // Random rays through the whole scene.
  Rng rng(702);
  for (std::uint32_t k = 0; k < 10 * n; ++k) {
    c.rays.push_back(Rec(rng.InBox(glm::dvec3(-9), glm::dvec3(9)), rng.UnitVector()));
    c.target.push_back(kAnyPrim);
  }
  return c;
}

// Degenerate pieces put straight into the scene's arrays (the loaders never
// produce them): zero-area triangles (collinear, repeated vertex, all three
// equal), a sphere of radius 0, a cone with both radii 0 (a segment); rays
// exactly along and through them.
HardCase RawPieces(const GenOptions& o)
{
  SceneBuilder b;
  b.Sphere({0, 0, 0}, 1.0);
  Scene& s = b.Get();
  auto rawTriangle = [&](const glm::vec3& a, const glm::vec3& bb, const glm::vec3& cc) {
    PrimInfo info;
    info.kind = PrimKind::kPolygon;
    info.type = CR_PRIM_TRIANGLE;
    info.nPieces = 1;
    cr::Triangle t{{a.x, a.y, a.z}, CR_TRI_REPORT_UV, {bb.x, bb.y, bb.z}, 0, {cc.x, cc.y, cc.z}, 0};
    t.flags |= TriangleEdgeFlags(t);
    info.firstPiece = s.AddPiece(t, s.NumPrims());
    s.prims.push_back(info);
  };
  rawTriangle({0, 0, 5}, {1, 1, 5}, {2, 2, 5});   // collinear
  rawTriangle({3, 0, 5}, {3, 0, 5}, {4, 1, 5});   // repeated vertex
  rawTriangle({5, 5, 5}, {5, 5, 5}, {5, 5, 5});   // a point
  {
    PrimInfo info;
    info.type = CR_PRIM_SPHERE;
    info.nPieces = 1;
    info.firstPiece = s.AddPiece(cr::Sphere{{4, 0, 0}, 0.0f}, s.NumPrims());
    s.prims.push_back(info);
  }
  {
    PrimInfo info;
    info.type = CR_PRIM_CONE;
    info.nPieces = 1;
    info.firstPiece = s.AddPiece(cr::Cone{{0, -8, 0}, 0.0f, {0, -8, 3}, 0.0f}, s.NumPrims());
    s.prims.push_back(info);
  }
  b.Sphere({6, 0, 0}, 1.0);
  b.Box(glm::dvec3(-30), glm::dvec3(30));
  HardCase c;
  c.name = "degenerate/raw-pieces";
  c.scene = b.Finish();
  c.expect = Expect::Reference;
  Rng rng(703);
  const std::size_t n = o.quick ? 100 : 1000;
  const glm::dvec3 aims[] = {{1, 1, 5}, {0, 0, 5},  {3, 0, 5},      {3.5, 0.5, 5},
                             {5, 5, 5}, {4, 0, 0},  {0, -8, 1.5},   {0, -8, 0}};
  for (const glm::dvec3& p : aims)
    for (std::size_t k = 0; k < n; ++k) {
      glm::dvec3 d;
      const double r = rng.Uniform();
      if (r < 0.3) {  // axis-parallel through the point
        d = glm::dvec3(0.0);
        d[rng.Below(3)] = rng.Uniform() < 0.5 ? 1.0 : -1.0;
      } else if (r < 0.5) {  // along the collinear triangle's line / the segment cone's axis
        d = p.z == 5.0 ? glm::dvec3(1, 1, 0) : glm::dvec3(0, 0, 1);
      } else {
        d = rng.UnitVector();
      }
      const double s2 = double(1 + rng.Below(8));
      c.rays.push_back(Rec(p - s2 * d, d));
    }
  return c;
}

// A closed mesh (icosphere-like: a bumpy sphere from the generator) for the
// grid-density case.
std::shared_ptr<const Scene> Ball(int n)
{
  SceneBuilder b;
  const double pi = 3.14159265358979323846;
  auto pt = [&](int i, int j) {
    const double th = pi * i / n, ph = 2.0 * pi * j / (2 * n);
    return glm::dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < 2 * n; ++j) {
      const glm::dvec3 a = pt(i, j), bb = pt(i + 1, j), cc = pt(i + 1, j + 1), d = pt(i, j + 1);
      if (i > 0) b.Triangle(a, bb, d);
      if (i < n - 1) b.Triangle(bb, cc, d);
    }
  return b.Finish();
}

std::vector<RayRecord> RandomRays(std::size_t n, double extent, std::uint64_t seed)
{
  Rng rng(seed);
  std::vector<RayRecord> rays;
  for (std::size_t k = 0; k < n; ++k)
    rays.push_back(Rec(rng.InBox(glm::dvec3(-extent), glm::dvec3(extent)), rng.UnitVector()));
  return rays;
}

HardCase GridDensity(const GenOptions& o)
{
  HardCase c;
  c.name = "extreme/grid-density-1e6";
  c.scene = Ball(o.quick ? 24 : 64);
  c.params.gridDensity = 1e6;
  c.accels = {AccelKind::Grid};
  c.build = BuildExpect::Warns;
  c.rays = RandomRays(o.quick ? 2000 : 20000, 1.5, 801);
  return c;
}

HardCase BadParam(const char* name, AccelKind accel, const AccelParams& params)
{
  HardCase c;
  c.name = name;
  c.scene = Ball(8);
  c.params = params;
  c.accels = {accel};
  c.build = BuildExpect::ThrowsInput;
  return c;
}

HardCase InputCoincident(const GenOptions& o)
{
  SceneBuilder b;
  for (int k = 0; k < 8; ++k) b.Sphere({8.0 * (k & 1), 8.0 * ((k >> 1) & 1), 8.0 * ((k >> 2) & 1)}, 0.1);
  const glm::dvec3 c0(3.3, 4.6, 5.1);
  for (int i = 0; i < 1000; ++i) b.Sphere(c0, 0.05);  // ids 8 .. 1007
  HardCase c;
  c.name = "extreme/coincident-at-depth-limit";
  c.scene = b.Finish();
  c.params.octreeLeaf = 1;
  c.params.octreeDepth = OctreeMaxDepth();
  c.params.bvhLeaf = 1;
  c.expect = Expect::Target;
  Rng rng(802);
  const std::size_t n = o.quick ? 500 : 5000;
  for (std::size_t k = 0; k < n; ++k) {
    // Through the cluster within 0.8 radii of its centre: the lowest id (8)
    // wins the exact tie of t.
    const glm::dvec3 d = rng.UnitVector();
    const glm::dvec3 side = glm::normalize(glm::cross(d, rng.UnitVector())) * (0.04 * std::sqrt(rng.Uniform()));
    c.rays.push_back(Rec(c0 + side - rng.Uniform(1.0, 3.0) * d, d));
    c.target.push_back(8);
  }
  return c;
}

}  // namespace

void AddDegenerateCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"degenerate/loader", "degenerate",
                   "NFF with a valid sphere (id 0), then a collinear triangle, a triangle with a repeated vertex, a "
                   "collinear quad, a sphere of radius 0, a cone with coincident ends, a cone with both radii 0, a "
                   "2-vertex polygon (ids 1..7: each skipped with a warning, id kept), then a hexagon with a repeated "
                   "and a collinear vertex, a sphere, a triangle, a cone, a patch (ids 8..12) and a backstop box. "
                   "Expect: at least 7 warnings; rays aimed at the valid primitives report their statement ids; all "
                   "others the reference's answer; no NaN.",
                   false, [](AccelKind, const GenOptions& o) { return Loader(o); }});
  specs.push_back({"degenerate/raw-pieces", "degenerate",
                   "Zero-area triangles (collinear, repeated vertex, a point), a sphere of radius 0 and a cone with "
                   "both radii 0 put straight into the scene's arrays, bypassing the loader; rays exactly through "
                   "and along them. Expect: the reference's answer, no NaN, no crash.",
                   false, [](AccelKind, const GenOptions& o) { return RawPieces(o); }});
}

void AddExtremeCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"extreme/grid-density-1e6", "extreme",
                   "--grid-density 1e6 on a closed mesh (10^9 .. 10^10 cells asked): clamped with a warning, then "
                   "the reference's answers (grid only).",
                   false, [](AccelKind, const GenOptions& o) { return GridDensity(o); }});
  specs.push_back({"extreme/grid-density-nan", "extreme", "--grid-density NaN: InputError (grid only).", false,
                   [](AccelKind, const GenOptions&) {
                     AccelParams p;
                     p.gridDensity = std::nan("");
                     return BadParam("extreme/grid-density-nan", AccelKind::Grid, p);
                   }});
  specs.push_back({"extreme/octree-depth-21", "extreme",
                   "--octree-depth 21 (past OctreeMaxDepth()): InputError (octree only).", false,
                   [](AccelKind, const GenOptions&) {
                     AccelParams p;
                     p.octreeDepth = OctreeMaxDepth() + 1;
                     return BadParam("extreme/octree-depth-21", AccelKind::Octree, p);
                   }});
  specs.push_back({"extreme/bvh-leaf-1000", "extreme", "--bvh-leaf 1000: InputError (bvh only).", false,
                   [](AccelKind, const GenOptions&) {
                     AccelParams p;
                     p.bvhLeaf = 1000;
                     return BadParam("extreme/bvh-leaf-1000", AccelKind::BVH, p);
                   }});
  specs.push_back({"extreme/coincident-at-depth-limit", "extreme",
                   "1000 coincident spheres with --octree-leaf 1 --octree-depth 20 (--bvh-leaf 1): the octree stops "
                   "at its depth limit, the BVH cannot split them. Expect: rays through the cluster report the "
                   "lowest id (the exact tie of t goes to the lower index).",
                   false, [](AccelKind, const GenOptions& o) { return InputCoincident(o); }});
}

}  // namespace cr::hard
