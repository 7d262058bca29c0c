// Self-intersection: secondary rays leaving hit points, as the renderer
// makes them (scene/surface.h: SurfaceAt reprojects the point in double,
// OffsetRayOrigin moves it off by the error bound), on spheres and cones of
// sizes 0.01 .. 100, on slivers, on a 10^4-wide quad seen near its middle,
// and on geometry at 10^5. Per hit: the mirror direction, random and
// grazing directions on the side the primary ray came from, a transmitted
// direction into the other side (whose origin is offset to that side), and
// a shadow ray to a light (tmax = 1). Primary hits come from the fp64
// reference, so the rays do not depend on the tracer under test.
#include <cmath>

#include "tests/hard/gen/hard_gen.h"
#include "host/reference/reference.h"
#include "host/scene/surface.h"

namespace cr::hard {

namespace {

struct View {
  glm::dvec3 eye, lo, hi;  // rays from eye to random points of [lo, hi]
};

HardCase SelfCase(const char* name, std::shared_ptr<const Scene> scene, const std::vector<View>& views,
                  const std::vector<glm::dvec3>& lights, std::size_t count, std::uint64_t seed)
{
  HardCase c;
  c.name = name;
  c.scene = scene;
  c.expect = Expect::NotSelf;
  const ref::ReferenceTracer tr(*scene);
  Rng rng(seed);
  auto push = [&](const glm::vec3& o, const glm::dvec3& d, std::uint32_t own, float tmax) {
    const RayRecord r = RecF(o, glm::vec3(d), 0.0f, tmax);
    if (r.dir[0] == 0.0f && r.dir[1] == 0.0f && r.dir[2] == 0.0f) return;
    c.rays.push_back(r);
    c.target.push_back(own);
    c.ownT.push_back(OwnRoot(tr, own, r, 0.0));
  };
  std::size_t attempts = 0;
  while (c.rays.size() < count && ++attempts < 100 * count) {
    const View& v = views[rng.Below(std::uint32_t(views.size()))];
    const RayRecord primary = Rec(v.eye, rng.InBox(v.lo, v.hi) - v.eye);
    const ref::RefHit h = tr.Intersect(ref::MakeRay(primary));
    if (!h.Found()) continue;
    const glm::dvec3 d = glm::normalize(D(primary.dir));
    const glm::dvec3 p = D(primary.org) + h.t * D(primary.dir);
    const SurfacePoint sp = SurfaceAt(*scene, h.g, p, h.u, h.v);
    const glm::dvec3 ng = D(sp.ng);
    const glm::dvec3 side = glm::dot(ng, d) < 0.0 ? ng : -ng;  // where the primary ray came from
    const glm::vec3 out = OffsetRayOrigin(sp.p, sp.error, glm::vec3(side));
    const glm::vec3 in = OffsetRayOrigin(sp.p, sp.error, glm::vec3(-side));
    const std::uint32_t own = scene->IdOfUnified(h.g);
    auto hemisphere = [&](const glm::dvec3& n) {
      glm::dvec3 u = rng.UnitVector();
      return glm::dot(u, n) < 0.0 ? -u : u;
    };
    push(out, d - 2.0 * glm::dot(d, side) * side, own, INFINITY);  // mirror
    push(out, hemisphere(side), own, INFINITY);
    {  // grazing: nearly tangent, leaving
      const glm::dvec3 t = glm::normalize(glm::cross(side, rng.UnitVector()));
      const double eps = std::ldexp(1.0, -int(4 + rng.Below(12)));
      push(out, t + eps * side, own, INFINITY);
    }
    push(in, hemisphere(-side), own, INFINITY);  // transmitted
    const glm::dvec3 l = lights[rng.Below(std::uint32_t(lights.size()))];
    const bool lit = glm::dot(l - p, side) > 0.0;
    const glm::vec3 so = lit ? out : in;
    push(so, l - D(so), own, 1.0f);  // shadow ray, tmax = 1
  }
  return c;
}

HardCase SelfCurved(const GenOptions& o)
{
  SceneBuilder b;
  b.Sphere({0, 0, 0}, 1.0);
  b.Sphere({3.3, -1.1, 0.4}, 0.01);
  b.Sphere({-250.5, 130.25, 40}, 100.0);
  b.Sphere({1000.3, 2000, -1000}, 5.0);
  b.Cone({5, 5, -1}, 0.5, {5, 5, 3}, 0.5);
  b.Cone({-6, 4, 0}, 1.5, {-6, 4, 4}, 0.2);
  b.Cone({-3, -8, 0}, 0.05, {40, -8, 1}, 0.05);
  b.Polygon({{-2000, -2000, -3}, {2000, -2000, -3}, {2000, 2000, -3}, {-2000, 2000, -3}});
  const std::vector<View> views = {
      {{0, -10, 3}, {-1, -1, -1}, {1, 1, 1}},
      {{3.25, -1.3, 0.5}, {3.29, -1.11, 0.39}, {3.31, -1.09, 0.41}},
      {{0, 0, 400}, {-350, 30, -60}, {-150, 230, 140}},
      {{1000, 1970, -1000}, {995, 1995, -1005}, {1005, 2005, -995}},
      {{8, 2, 2}, {4.5, 4.5, -1}, {5.5, 5.5, 3}},
      {{-6, -2, 3}, {-7.5, 2.5, 0}, {-4.5, 5.5, 4}},
      {{10, -12, 3}, {-3, -8.05, -0.05}, {40, -7.95, 1.05}},
      {{1, 1, 2}, {-20, -20, -3}, {20, 20, -3}},
  };
  return SelfCase("self/curved", b.Finish(), views, {{50, -50, 100}, {-1000, 500, 800}}, o.quick ? 3000 : 30000, 601);
}

HardCase SelfPlanar(const GenOptions& o)
{
  SceneBuilder b;
  b.Triangle({0, 0, 0}, {100, 0, 0}, {100, 1e-3, 1e-4});        // sliver
  b.Triangle({0, 0, 1}, {0.001, 50, 1}, {-0.002, 50, 1.0005});  // sliver
  b.Triangle({-10, 3, -2}, {10, 3.0001, 2}, {-10, 3.0002, 2});  // thin, tilted
  b.Polygon({{-5e3, -5e3, -1}, {5e3, -5e3, -1}, {5e3, 5e3, -1}, {-5e3, 5e3, -1}});  // 10^4 wide
  const std::vector<View> views = {
      {{50, -3, 2}, {0, 0, -0.0001}, {100, 0.001, 0.0001}},
      {{5, 25, 3}, {-0.002, 0, 0.999}, {0.001, 50, 1.001}},
      {{0, -5, 0.5}, {-10, 3, -2}, {10, 3.0002, 2}},
      {{0.3, 0.2, 5}, {-2, -2, -1}, {2, 2, -1}},
      {{-0.7, 1.3, 0.2}, {-1, -1, -1}, {1, 1, -1}},
  };
  return SelfCase("self/planar", b.Finish(), views, {{3, 4, 50}, {-80, 30, 20}}, o.quick ? 3000 : 30000, 602);
}

HardCase FarPlane(const GenOptions& o)
{
  SceneBuilder b;
  const glm::dvec3 c(1e5, 1e5, 1e5);
  b.Polygon({c + glm::dvec3(-500, -500, 0), c + glm::dvec3(500, -500, 0), c + glm::dvec3(500, 500, 0),
             c + glm::dvec3(-500, 500, 0)});
  b.Sphere(c + glm::dvec3(30, 0, 10), 10.0);
  b.Cone(c + glm::dvec3(-40, 0, 0), 3.0, c + glm::dvec3(-40, 0, 30), 3.0);
  const glm::dvec3 eye = c + glm::dvec3(0, -60, 50);
  const std::vector<View> views = {
      {eye, c + glm::dvec3(-5, -5, 0), c + glm::dvec3(5, 5, 0)},
      {eye, c + glm::dvec3(20, -10, 0), c + glm::dvec3(40, 10, 20)},
      {eye, c + glm::dvec3(-43, -3, 0), c + glm::dvec3(-37, 3, 30)},
  };
  return SelfCase("self/far-plane", b.Finish(), views, {c + glm::dvec3(100, -200, 300)}, o.quick ? 3000 : 30000, 603);
}

}  // namespace

void AddSelfCases(std::vector<CaseSpec>& specs)
{
  const char* expect =
      " Expect: the reference's answer, and the ray's own primitive only where the reference meets it again away "
      "from the origin (t >= half its first root there; occlusion: that root within tmax); a convex or flat surface "
      "left on its outer side is never reported.";
  specs.push_back({"self/curved", "self",
                   std::string("Spheres of radius 1, 0.01, 100 (at 250) and 5 (at 2000), a cylinder, a cone, a thin "
                               "cylinder 43 long, a 4000-wide ground quad.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return SelfCurved(o); }});
  specs.push_back({"self/planar", "self",
                   std::string("Slivers (100 x 0.001, 50 x 0.002), a thin tilted triangle and a 10^4-wide quad seen "
                               "near its middle.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return SelfPlanar(o); }});
  specs.push_back({"self/far-plane", "self",
                   std::string("A 1000-wide quad in the plane z = 1e5, a sphere and a cylinder beside it, all at "
                               "coordinates 1e5, camera 80 away.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return FarPlane(o); }});
}

}  // namespace cr::hard
