// Huge primitives and mixed scales: the classic ground made of a sphere of
// radius ~1e6 whose centre lies a million units below the camera, triangles
// 1e6 across seen from 10..100 away, a cylinder of radius 1e6 used the same
// way, and scenes mixing such primitives with features of 1e-4.
//
// What these test. A float intersector that subtracts the primitive's own
// coordinates (o - c for a sphere centred 1e6 away, v - o for a vertex 5e5
// away) rounds at the spacing of those coordinates, 0.06 at 1e6, while the
// hit lies 10..100 units from the ray origin: t comes out with a relative
// error of 1e-4..1e-3 (|f|^2 - r^2 alone loses 16 bits for the ground
// sphere). check.h's tolerance belongs to the ray and its hit (2^-16 of
// |o| + t |d|), not to the primitive's size, so such an error is wrong, and
// a small object sitting on the ground can be hidden behind a ground hit
// placed in front of it. Robust mode computes what cancels in double-float
// (kernels/intersect.h), so its t stays within a few ulps.
//
// Expectations: rays whose reference hit is robust (the surface met at an
// angle, away from triangle edges and cone rims) must report that
// primitive with t within 2^-20 relative of the reference's; all others the
// reference's answer under check.h.
#include <array>
#include <cmath>

#include "tests/hard/gen/hard_gen.h"
#include "host/reference/reference.h"

namespace cr::hard {

namespace {

constexpr double kHugeRelTolT = 0x1p-20;

// Target id of one ray from the reference: the primitive it hits, when the
// hit is robust (|cos| of the angle to the normal >= minCos, and on
// triangles every barycentric >= edgeFrac, on cones the axial position
// inside the rim by edgeFrac of the height, on boxes the point inside its
// face by edgeFrac of the face's extent); else kAnyPrim.
std::uint32_t RobustTarget(const ref::ReferenceTracer& tr, const RayRecord& rec, double minCos, double edgeFrac)
{
  const ref::DRay r = ref::MakeRay(rec);
  const ref::RefHit h = tr.Intersect(r);
  if (!h.Found()) return kAnyPrim;
  const Scene& scene = tr.GetScene();
  const PrimRanges n = scene.Ranges();
  const glm::dvec3 p = r.o + h.t * r.d;
  const double c = std::fabs(glm::dot(tr.GeometricNormal(h.g, p), glm::normalize(r.d)));
  if (c < minCos) return kAnyPrim;
  if (Prim_Is(&n, CR_PRIM_TRIANGLE, h.g)) {
    if (std::min({h.u, h.v, 1.0 - h.u - h.v}) < edgeFrac) return kAnyPrim;
  } else if (Prim_Is(&n, CR_PRIM_CONE, h.g)) {
    const Cone& cn = scene.cones[Prim_Local(&n, CR_PRIM_CONE, h.g)];
    const glm::dvec3 b = D(cn.base), w = D(cn.apex) - b;
    const double s = glm::dot(p - b, w) / glm::dot(w, w);
    if (s < edgeFrac || s > 1.0 - edgeFrac) return kAnyPrim;
  } else if (Prim_Is(&n, CR_PRIM_BOX, h.g)) {
    const Box& bx = scene.boxes[Prim_Local(&n, CR_PRIM_BOX, h.g)];
    const glm::dvec3 lo = D(bx.lo), hi = D(bx.hi), nrm = tr.GeometricNormal(h.g, p);
    for (int a = 0; a < 3; ++a) {
      if (nrm[a] != 0.0) continue;  // the face's own axis
      const double m = edgeFrac * (hi[a] - lo[a]);
      if (p[a] < lo[a] + m || p[a] > hi[a] - m) return kAnyPrim;
    }
  } else if (Prim_Is(&n, CR_PRIM_QUADRIC, h.g)) {
    const Quadric& q = scene.quadrics[Prim_Local(&n, CR_PRIM_QUADRIC, h.g)];
    for (int a = 0; a < 3; ++a)  // inside the clip box, away from the rim
      if (std::fabs(p[a] - double(q.center[a])) > (1.0 - edgeFrac) * double(q.extent[a])) return kAnyPrim;
  } else if (Prim_Is(&n, CR_PRIM_POLYHEDRON, h.g)) {
    // Away from the edges: one face's plane through the point, every other
    // plane's distance from it more than edgeFrac of the solid's size.
    const Polyhedron& ph = scene.polyhedra[Prim_Local(&n, CR_PRIM_POLYHEDRON, h.g)];
    const double size = glm::length(D(ph.hi) - D(ph.lo));
    int near = 0;
    for (std::uint32_t k = 0; k < ph.count; ++k) {
      const glm::dvec3 nk = D(ph.plane[k]);
      const double v = (glm::dot(nk, p - D(ph.center)) + double(ph.plane[k][3])) / glm::length(nk);
      if (std::fabs(v) <= edgeFrac * size) ++near;
    }
    if (near != 1) return kAnyPrim;
  }
  return scene.IdOfUnified(h.g);
}

// Fills c.target from the reference (RobustTarget per ray).
void SetTargets(HardCase& c, double minCos, double edgeFrac)
{
  const ref::ReferenceTracer tr(*c.scene);
  c.target.resize(c.rays.size());
  for (std::size_t i = 0; i < c.rays.size(); ++i) c.target[i] = RobustTarget(tr, c.rays[i], minCos, edgeFrac);
}

// A case of the family: its scene, judged by robust targets (SetTargets).
HardCase TargetCase(const char* name, SceneBuilder& b)
{
  HardCase c;
  c.name = name;
  c.scene = b.Finish();
  c.expect = Expect::Target;
  c.relTolT = kHugeRelTolT;
  return c;
}

// Unit vector at polar angle theta from axis n (unit), azimuth phi.
glm::dvec3 AroundAxis(const glm::dvec3& n, double theta, double phi)
{
  const glm::dvec3 a = std::fabs(n.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  const glm::dvec3 e1 = glm::normalize(glm::cross(n, a)), e2 = glm::cross(n, e1);
  return std::cos(theta) * n + std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2);
}

// A ground sphere: centre R0 below the origin along -up, radius R0 - 1 (its
// top one unit below the origin). Cameras at heights 10, 30 and 100 above the
// top, some beside the top point, looking down at every angle up to past the
// horizon (those rays miss), plus rays aimed at points of the ground 1..1e4
// away. `up` is exact in float times R0 (e.g. (0.6, 0.8, 0): centre
// (-6e5, -8e5, 0)).
HardCase GroundSphere(const char* name, double R0, const glm::dvec3& up, const GenOptions& o)
{
  Rng rng(501);
  SceneBuilder b;
  const glm::dvec3 centre = -R0 * up;
  b.Sphere(centre, R0 - 1.0);
  HardCase c = TargetCase(name, b);
  const std::size_t n = o.quick ? 1500 : 15000;
  const double heights[] = {10.0, 30.0, 100.0};
  const glm::dvec3 side = glm::normalize(glm::cross(up, glm::dvec3(0.0, 0.0, 1.0) + 0.3 * up));
  for (std::size_t k = 0; k < n; ++k) {
    const double h = heights[k % 3];
    // Camera over the top point, or up to 1000 units beside it (still h
    // above the surface, to first order).
    const double off = (k / 3) % 2 == 0 ? 0.0 : rng.Uniform(-1000.0, 1000.0);
    const glm::dvec3 foot = centre + (R0 - 1.0) * glm::normalize(-centre + off * side);
    const glm::dvec3 nrm = glm::normalize(foot - centre);
    const glm::dvec3 cam = foot + h * nrm;
    glm::dvec3 dir;
    if (k % 4 == 3) {
      // Aimed at a ground point 1..1e4 away along the surface.
      const double dist = std::exp(rng.Uniform(0.0, std::log(1e4)));
      const glm::dvec3 tang = AroundAxis(nrm, kPi / 2, rng.Uniform(0.0, 2 * kPi));
      const glm::dvec3 g = centre + (R0 - 1.0) * glm::normalize(foot + dist * tang - centre);
      dir = g - cam;
    } else {
      // Polar angle from the nadir up to 95 degrees (the horizon of h = 10
      // lies at 89.8 degrees).
      const double theta = kPi * rng.Uniform(0.0, 95.0 / 180.0);
      dir = AroundAxis(-nrm, theta, rng.Uniform(0.0, 2 * kPi)) * rng.Uniform(0.5, 4.0);
    }
    c.rays.push_back(Rec(cam, dir));
  }
  SetTargets(c, 0.05, 0.0);
  return c;
}

// Two triangle statements forming a quad 1e6 across in a tilted plane one
// unit below the origin, the shared diagonal passing under the cameras;
// cameras 10..100 above the plane near the origin and 3e5 away from it.
HardCase TiltedTriangles(const GenOptions& o)
{
  Rng rng(502);
  const glm::dvec3 nrm = glm::normalize(glm::dvec3(0.28, 0.96, 0.17));
  const glm::dvec3 e1 = glm::normalize(glm::cross(nrm, glm::dvec3(0, 0, 1)));
  const glm::dvec3 e2 = glm::cross(nrm, e1);
  const glm::dvec3 p0 = -1.0 * nrm;
  const double H = 5e5;
  const glm::dvec3 q00 = p0 - H * e1 - H * e2, q10 = p0 + H * e1 - H * e2, q11 = p0 + H * e1 + H * e2,
                   q01 = p0 - H * e1 + H * e2;
  SceneBuilder b;
  b.Triangle(q00, q10, q11);
  b.Triangle(q00, q11, q01);
  // A second pair, steeper, 2e6 across, far to one side: the cameras near it
  // have |o| ~ 3e5.
  const glm::dvec3 n2 = glm::normalize(glm::dvec3(-0.5, 0.7, 0.5));
  const glm::dvec3 f1 = glm::normalize(glm::cross(n2, glm::dvec3(1, 0, 0))), f2 = glm::cross(n2, f1);
  const glm::dvec3 p2 = glm::dvec3(3e5, -2e5, 1e5);
  b.Triangle(p2 - 1e6 * f1 - 1e6 * f2, p2 + 1e6 * f1 - 1e6 * f2, p2 + 1e6 * f1 + 1e6 * f2);
  b.Triangle(p2 - 1e6 * f1 - 1e6 * f2, p2 + 1e6 * f1 + 1e6 * f2, p2 - 1e6 * f1 + 1e6 * f2);
  HardCase c = TargetCase("huge/tilted-triangles", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    const bool second = k % 3 == 2;
    const glm::dvec3 pn = second ? n2 : nrm, pa = second ? f1 : e1, pb = second ? f2 : e2;
    const glm::dvec3 base = second ? p2 + rng.Uniform(-50.0, 50.0) * pa : p0;
    const double h = std::exp(rng.Uniform(std::log(10.0), std::log(100.0)));
    // The camera beside the diagonal (pa + pb direction) by up to 30 units.
    const glm::dvec3 cam = base + h * pn + rng.Uniform(-30.0, 30.0) * glm::normalize(pa - pb);
    glm::dvec3 target;
    if (k % 5 == 0) {
      // A point of the shared diagonal (exactly on it up to rounding).
      target = base + rng.Uniform(-300.0, 300.0) * glm::normalize(pa + pb);
    } else {
      const double dist = std::exp(rng.Uniform(0.0, std::log(3000.0)));
      const double phi = rng.Uniform(0.0, 2 * kPi);
      target = base + dist * (std::cos(phi) * pa + std::sin(phi) * pb);
    }
    c.rays.push_back(Rec(cam, (target - cam) * rng.Uniform(0.5, 2.0)));
  }
  // Edges: a barycentric below 1e-7 (0.1 units of a 1e6 triangle) is near
  // the diagonal; those rays are judged as the reference's answer.
  SetTargets(c, 0.05, 1e-7);
  return c;
}

// A cylinder of radius 1e6 - 1 lying along z a million units below, as a
// ground, and a thin cone 1e6 long (radius 1 to 2) seen from 20..100 away.
HardCase HugeCones(const GenOptions& o)
{
  Rng rng(503);
  SceneBuilder b;
  const double R0 = 1e6;
  b.Cone({0.0, -R0, -R0}, R0 - 1.0, {0.0, -R0, R0}, R0 - 1.0);
  b.Cone({-5e5, 50.0, -200.0}, 1.0, {5e5, 50.0, -200.0}, 2.0);
  HardCase c = TargetCase("huge/cones", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    glm::dvec3 cam, dir;
    if (k % 2 == 0) {
      // Down at the cylinder ground from 10..100 above its top line.
      cam = {rng.Uniform(-500.0, 500.0), std::exp(rng.Uniform(std::log(10.0), std::log(100.0))),
             rng.Uniform(-1e4, 1e4)};
      const double theta = kPi * rng.Uniform(0.0, 95.0 / 180.0);
      dir = AroundAxis({0.0, -1.0, 0.0}, theta, rng.Uniform(0.0, 2 * kPi));
    } else {
      // At the thin cone, from 20..100 away, at points along 2000 units of it.
      const double x = rng.Uniform(-1000.0, 1000.0);
      const double rad = 1.0 + (x + 5e5) / 1e6;
      const glm::dvec3 axisPt(x, 50.0, -200.0);
      const glm::dvec3 aim = axisPt + AroundAxis({1.0, 0.0, 0.0}, kPi / 2, rng.Uniform(0.0, 2 * kPi)) *
                                         (rad * rng.Uniform(0.0, 1.3));
      cam = axisPt + AroundAxis({1.0, 0.0, 0.0}, kPi / 2, rng.Uniform(0.0, 2 * kPi)) * rng.Uniform(20.0, 100.0) +
            glm::dvec3(rng.Uniform(-50.0, 50.0), 0.0, 0.0);
      dir = aim - cam;
    }
    c.rays.push_back(Rec(cam, dir));
  }
  SetTargets(c, 0.05, 1e-6);
  return c;
}

// Features of 1e-4 on huge ground primitives: a ground sphere (R0 = 1e6) and
// a huge tilted triangle pair beside it, with spheres of radius 1e-4,
// triangles 2e-4 across and a thin cylinder of radius 1e-4 standing on the
// ground near the origin; cameras 0.01..1 away, rays aimed at the small
// features and the ground between them.
HardCase Mixed(const GenOptions& o)
{
  Rng rng(504);
  SceneBuilder b;
  const double R0 = 1e6;
  const glm::dvec3 centre(0.0, -R0, 0.0);
  b.Sphere(centre, R0);  // top at y = 0
  // The ground continues as a tilted plane from x = 5 on (it cuts the sphere
  // there), 1e6 across.
  const glm::dvec3 tn = glm::normalize(glm::dvec3(-0.05, 1.0, 0.02));
  const glm::dvec3 t1 = glm::normalize(glm::cross(tn, glm::dvec3(0, 0, 1))), t2 = glm::cross(tn, t1);
  const glm::dvec3 tp(5.0, 0.0, 0.0);
  b.Triangle(tp - 5e5 * t1 - 5e5 * t2, tp + 5e5 * t1 - 5e5 * t2, tp + 5e5 * t1 + 5e5 * t2);
  std::vector<glm::dvec3> feature;
  for (int i = 0; i < 12; ++i) {
    const double x = rng.Uniform(-0.05, 0.05), z = rng.Uniform(-0.05, 0.05);
    // The sphere's surface height at (x, z): -(x^2 + z^2) / (2 R0) to first order.
    const double y = -(x * x + z * z) / (2.0 * R0);
    const glm::dvec3 g(x, y, z);
    switch (i % 3) {
      case 0: b.Sphere(g + glm::dvec3(0.0, 1e-4, 0.0), 1e-4); break;
      case 1: b.Triangle(g + glm::dvec3(-1e-4, 0.0, 0.0), g + glm::dvec3(1e-4, 0.0, 0.0), g + glm::dvec3(0.0, 2e-4, 1e-4)); break;
      default: b.Cone(g - glm::dvec3(0.0, 1e-4, 0.0), 1e-4, g + glm::dvec3(0.0, 3e-4, 0.0), 1e-4); break;
    }
    feature.push_back(g + glm::dvec3(0.0, 1e-4, 0.0));
  }
  HardCase c = TargetCase("huge/mixed-scales", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::dvec3 f = feature[k % feature.size()];
    const double dist = std::exp(rng.Uniform(std::log(0.01), std::log(1.0)));
    // From above at 10..80 degrees of elevation.
    const glm::dvec3 from = AroundAxis({0.0, 1.0, 0.0}, kPi * rng.Uniform(10.0, 80.0) / 180.0, rng.Uniform(0.0, 2 * kPi));
    const glm::dvec3 cam = f + dist * from;
    const glm::dvec3 aim = f + rng.Uniform(0.0, 3e-4) * AroundAxis({0.0, 1.0, 0.0}, kPi / 2, rng.Uniform(0.0, 2 * kPi)) +
                           glm::dvec3(0.0, rng.Uniform(-1e-4, 1e-4), 0.0);
    c.rays.push_back(Rec(cam, aim - cam));
  }
  SetTargets(c, 0.05, 1e-3);
  return c;
}

// A box primitive 2e6 across whose top face (y = -1) is the ground, a small
// box standing on it; cameras 10..100 above, rays down at every angle up to
// 85 degrees from the vertical and at the small box. The slab parameters
// (p - o) / d of the top face are exact or once rounded, so t stays within
// an ulp or two however far the box's other faces are.
HardCase GroundBox(const GenOptions& o)
{
  Rng rng(507);
  SceneBuilder b;
  b.AxisBox({-1e6, -1e6, -1e6}, {1e6, -1.0, 1e6});
  b.AxisBox({2.0, -1.0, 3.0}, {2.5, -0.5, 3.5});
  HardCase c = TargetCase("huge/ground-box", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::dvec3 cam = {rng.Uniform(-500.0, 500.0), -1.0 + std::exp(rng.Uniform(std::log(10.0), std::log(100.0))),
                            rng.Uniform(-500.0, 500.0)};
    glm::dvec3 dir;
    if (k % 3 == 2) {
      dir = glm::dvec3(rng.Uniform(2.0, 2.5), rng.Uniform(-1.0, -0.5), rng.Uniform(3.0, 3.5)) - cam;
    } else {
      const double theta = kPi * rng.Uniform(0.0, 85.0 / 180.0);
      dir = AroundAxis({0.0, -1.0, 0.0}, theta, rng.Uniform(0.0, 2 * kPi));
    }
    c.rays.push_back(Rec(cam, dir));
  }
  SetTargets(c, 0.05, 1e-6);
  return c;
}

// Convex polyhedra (`polyhedron`): a cube, an octahedron and a thin tilted
// slab near the origin, the same three 1e6 away; rays from 5..50 away at
// points of their faces, at their edges and vertices (and a float step off
// them), and in the planes of the cube's faces.
HardCase Polyhedra(const GenOptions& o)
{
  Rng rng(523);
  SceneBuilder b;
  std::vector<glm::dvec3> centres = {{0.0, 0.0, 0.0}, {1e6, 0.0, 1e6}};
  std::vector<std::vector<glm::dvec3>> vertices;
  for (const glm::dvec3& c : centres) {
    std::vector<glm::dvec4> cube, octa, slab;
    for (int a = 0; a < 3; ++a)
      for (double s : {-1.0, 1.0}) {
        glm::dvec4 p(0.0);
        p[a] = s;
        p.w = -(s * c[a] + 1.0);
        cube.push_back(p);
      }
    const glm::dvec3 oc = c + glm::dvec3(4.0, 0.0, 0.0);
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 nn(k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1);
      octa.push_back(glm::dvec4(nn, -(glm::dot(nn, oc) + 1.5)));
    }
    const glm::dvec3 sc = c + glm::dvec3(-4.0, 0.0, 0.0), sn(0.6, 0.8, 0.0);
    slab = {glm::dvec4(sn, -(glm::dot(sn, sc) + 0.01)), glm::dvec4(-sn, glm::dot(sn, sc) - 0.01),
            {0, 0, 1, -(sc.z + 1.0)}, {0, 0, -1, sc.z - 1.0}, {0.8, -0.6, 0, -(0.8 * sc.x - 0.6 * sc.y + 1.0)},
            {-0.8, 0.6, 0, 0.8 * sc.x - 0.6 * sc.y - 1.0}};
    b.Polyhedron(cube);
    b.Polyhedron(octa);
    b.Polyhedron(slab);
    std::vector<glm::dvec3> v;
    for (int k = 0; k < 8; ++k) v.push_back(c + glm::dvec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1));
    for (int a = 0; a < 3; ++a)
      for (double s : {-1.5, 1.5}) {
        glm::dvec3 q = oc;
        q[a] += s;
        v.push_back(q);
      }
    vertices.push_back(v);
  }
  // a marker triangle: the type set of tests/test_polyhedron.cpp's scenes
  b.Triangle({-8.0, 0.0, -6.0}, {-6.0, 0.0, -6.0}, {-7.0, 1.5, -6.0});
  HardCase c = TargetCase("huge/polyhedra", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t which = k % 2;
    const glm::dvec3& base = centres[which];
    const std::vector<glm::dvec3>& v = vertices[which];
    glm::dvec3 target;
    switch (k % 5) {
      case 0: target = v[rng.Below(std::uint32_t(v.size()))]; break;                       // a vertex
      case 1: {                                                             // an edge point
        const glm::dvec3 a = v[rng.Below(8)];
        glm::dvec3 e = a;
        const int axis = int(rng.Below(3));
        e[axis] = base[axis] - (a[axis] - base[axis]);
        target = a + rng.Uniform(0.0, 1.0) * (e - a);
        break;
      }
      case 2: {  // in a cube face's plane, running along it
        const int axis = int(rng.Below(3));
        glm::dvec3 o0 = base + glm::dvec3(rng.Uniform(-1.2, 1.2), rng.Uniform(-1.2, 1.2), rng.Uniform(-1.2, 1.2));
        o0[axis] = base[axis] + (rng.Below(2) ? 1.0 : -1.0);
        glm::dvec3 d(rng.Uniform(-1.0, 1.0), rng.Uniform(-1.0, 1.0), rng.Uniform(-1.0, 1.0));
        d[axis] = 0.0;
        const glm::dvec3 from = o0 - 20.0 * d;
        c.rays.push_back(Rec(from, d));
        continue;
      }
      default:
        target = base + glm::dvec3(rng.Uniform(-5.0, 5.0), rng.Uniform(-1.6, 1.6), rng.Uniform(-1.6, 1.6));
        break;
    }
    const glm::dvec3 away = AroundAxis({0.0, 0.0, 1.0}, rng.Uniform(0.0, kPi), rng.Uniform(0.0, 2 * kPi));
    const glm::dvec3 cam = base + std::exp(rng.Uniform(std::log(5.0), std::log(50.0))) * away;
    glm::dvec3 dir = target - cam;
    if (k % 7 == 3) dir += glm::dvec3(std::nextafter(float(dir.x), INFINITY) - float(dir.x), 0.0, 0.0);
    c.rays.push_back(Rec(cam, dir));
  }
  SetTargets(c, 0.05, 1e-4);
  // A ray aimed at a vertex or an edge may touch that solid at one point
  // (or pass it by an ulp) before the surface the reference meets: those
  // are judged by check's tolerance (the reference's answer), not by id.
  for (std::size_t k = 0; k < c.rays.size(); ++k)
    if (k % 5 <= 1) c.target[k] = kAnyPrim;
  return c;
}

// The ground of GroundSphere as a quadric: the ellipsoid x^2 + 4 (y + 5e5)^2
// + z^2 = 1e12 (semi-axes 1e6, 5e5, 1e6, its top at y = 0) clipped to
// y >= -10, with a paraboloid bowl y = (x^2 + z^2) / 4 and a tilted
// hyperboloid of one sheet on it (and a small triangle); cameras 10..100 above, rays down at every
// angle up to 85 degrees from the vertical and at the two small quadrics.
// The ground's c = f(o - centre) cancels 13 bits in float, as the ground
// sphere's |f|^2 - r^2 does.
HardCase GroundQuadric(const GenOptions& o)
{
  Rng rng(511);
  SceneBuilder b;
  b.Quadric({1, 4, 1, 0, 0, 0, 0, 4e6, 0, 0}, {-1e6, -10.0, -1e6}, {1e6, 1.0, 1e6});
  b.Quadric({0.25, 0, 0.25, 0, 0, 0, 0, -1, 0, 0}, {-3.0, 0.0, -3.0}, {3.0, 2.25, 3.0});
  // (x - 8)^2 + (z - 2)^2 - (y - 2)^2 / 4 + 0.3 x y = 1, clipped to a box around it
  b.Quadric({1, -0.25, 1, 0.3, 0, 0, -16, 1, -4, 8 * 8 + 4 - 1 - 1}, {5.0, 0.0, -1.0}, {11.0, 4.0, 5.0});
  // a marker triangle beside them: the scene's type set is the quadric scenes' of
  // tests/test_quadric.cpp, so the OpenCL programs compile once for both
  b.Triangle({-8.0, 0.0, -6.0}, {-6.0, 0.0, -6.0}, {-7.0, 1.5, -6.0});
  HardCase c = TargetCase("huge/ground-quadric", b);
  const std::size_t n = o.quick ? 1500 : 15000;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::dvec3 cam = {rng.Uniform(-500.0, 500.0), std::exp(rng.Uniform(std::log(10.0), std::log(100.0))),
                            rng.Uniform(-500.0, 500.0)};
    glm::dvec3 dir;
    if (k % 3 == 2) {
      dir = (k % 2 ? glm::dvec3(rng.Uniform(-3.0, 3.0), rng.Uniform(0.0, 2.0), rng.Uniform(-3.0, 3.0))
                   : glm::dvec3(rng.Uniform(5.0, 11.0), rng.Uniform(0.0, 4.0), rng.Uniform(-1.0, 5.0))) -
            cam;
    } else {
      const double theta = kPi * rng.Uniform(0.0, 85.0 / 180.0);
      dir = AroundAxis({0.0, -1.0, 0.0}, theta, rng.Uniform(0.0, 2 * kPi));
    }
    c.rays.push_back(Rec(cam, dir));
  }
  SetTargets(c, 0.05, 1e-3);
  return c;
}

// Small primitives seen from far away, the origins in or near their planes
// (a random ray from a corner of a scene that holds a ground sphere): the
// triangle is seen edge-on, every edge function lies below its rounding and
// two can round to 0 while the third does not, an "inside" 10^6 away from
// the triangle unless the degenerate projection is caught.
HardCase FarOrigins(const GenOptions& o)
{
  Rng rng(505);
  SceneBuilder b;
  std::vector<std::array<glm::dvec3, 3>> tris;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 c = rng.InBox({-10, -10, -10}, {10, 10, 10});
    const std::array<glm::dvec3, 3> t = {c + rng.UnitVector() * rng.Uniform(0.5, 3.0),
                                         c + rng.UnitVector() * rng.Uniform(0.5, 3.0),
                                         c + rng.UnitVector() * rng.Uniform(0.5, 3.0)};
    b.Triangle(t[0], t[1], t[2]);
    tris.push_back(t);
  }
  for (int i = 0; i < 4; ++i) b.Sphere(rng.InBox({-10, -10, -10}, {10, 10, 10}), rng.Uniform(0.5, 2.0));
  b.Cone({-3, -8, 2}, 1.0, {4, -6, 1}, 0.5);
  HardCase c;
  c.name = "huge/far-origins";
  c.scene = b.Finish();
  c.expect = Expect::Reference;
  const std::size_t n = o.quick ? 3000 : 30000;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& t = tris[k % tris.size()];
    const glm::dvec3 nrm = glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
    const glm::dvec3 centre = (t[0] + t[1] + t[2]) / 3.0;
    // An origin 1e5..2e6 away, in the triangle's plane up to 0..1e-3 of the
    // distance.
    const double dist = std::exp(rng.Uniform(std::log(1e5), std::log(2e6)));
    glm::dvec3 along = rng.UnitVector();
    along = glm::normalize(along - glm::dot(along, nrm) * nrm);
    const glm::dvec3 org = centre + dist * along + nrm * (dist * 1e-3 * rng.Uniform(-1.0, 1.0) * (k % 3 == 0));
    glm::dvec3 dir;
    if (k % 2 == 0) dir = rng.UnitVector() * rng.Uniform(0.5, 2.0);                      // anywhere
    else dir = (centre + rng.UnitVector() * rng.Uniform(0.0, 3.0)) - org;                // at the triangle
    c.rays.push_back(Rec(org, dir));
  }
  return c;
}

// Tiny triangles (1e-3..1e-2 across) standing on a ground sphere of radius
// 1e5, rays from 1e4..1e5 away: at the rays' origins float's spacing exceeds
// the triangles, v - o rounds their vertices together and the float edge
// functions are all noise (two can be exactly 0 and the third not: Woop's
// test reads "inside" at the plane's crossing, which can lie anywhere). A
// uniform grid or octree tests them whenever the ray crosses the coarse cell
// they share with the ground. Found by bench/stress_scales.py (seed 3: a
// false hit 3e4 from a triangle 1e-3 across).
HardCase TinyTrianglesFar(const GenOptions& o)
{
  Rng rng(506);
  SceneBuilder b;
  b.Sphere({0, -1e5, 0}, 1e5);
  struct Tri {
    glm::dvec3 c, n;
    double size;
  };
  std::vector<Tri> tris;
  for (int i = 0; i < 60; ++i) {
    const double size = std::exp(rng.Uniform(std::log(1e-3), std::log(1e-2)));
    const glm::dvec3 c = rng.InBox({-300, 0.5, -300}, {300, 5, 300});
    const glm::dvec3 v0 = c + rng.UnitVector() * size, v1 = c + rng.UnitVector() * size,
                     v2 = c + rng.UnitVector() * size;
    b.Triangle(v0, v1, v2);
    tris.push_back({c, glm::normalize(glm::cross(v1 - v0, v2 - v0)), size});
  }
  HardCase c;
  c.name = "huge/tiny-triangles-far";
  c.scene = b.Finish();
  c.expect = Expect::Reference;
  const std::size_t n = o.quick ? 4000 : 40000;
  for (std::size_t k = 0; k < n; ++k) {
    const Tri& t = tris[rng.Below(std::uint32_t(tris.size()))];
    const double dist = std::exp(rng.Uniform(std::log(1e4), std::log(1e5)));
    glm::dvec3 up = rng.UnitVector();
    up.y = std::abs(up.y);
    const glm::dvec3 org = t.c + dist * up;
    glm::dvec3 at;
    switch (k % 4) {
      case 0: at = org + rng.UnitVector(); break;                                    // anywhere
      case 1: at = t.c + rng.UnitVector() * (t.size * rng.Uniform(0.0, 2.0)); break;  // at the triangle
      case 2: {  // a point of its plane 10..3e4 away: the crossing a false hit reports
        glm::dvec3 a = rng.UnitVector();
        a = glm::normalize(a - glm::dot(a, t.n) * t.n);
        at = t.c + a * std::exp(rng.Uniform(std::log(10.0), std::log(3e4)));
        break;
      }
      default: at = t.c + rng.UnitVector() * std::exp(rng.Uniform(0.0, std::log(1e3)));  // near it
    }
    c.rays.push_back(Rec(org, at - org));
  }
  return c;
}

}  // namespace

void AddHugeCases(std::vector<CaseSpec>& specs)
{
  const char* expect =
      " Expect: rays whose reference hit is robust (met at more than 3 degrees from the tangent plane, away from "
      "edges and rims) the primitive's id and t within 2^-20 relative of the reference's; all others the "
      "reference's answer under check.h's tolerance.";
  specs.push_back({"huge/ground-sphere-1e6", "huge",
                   std::string("A ground sphere: centre 1e6 below the origin, radius 1e6 - 1; cameras 10, 30 and 100 "
                               "above it, over its top and up to 1000 beside it; rays down at every angle to past "
                               "the horizon, and aimed at ground points 1..1e4 away.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) {
                     return GroundSphere("huge/ground-sphere-1e6", 1e6, {0.0, 1.0, 0.0}, o);
                   }});
  specs.push_back({"huge/ground-sphere-tilted", "huge",
                   std::string("As ground-sphere-1e6 with the centre in general position, (-6e5, -8e5, 0).") + expect,
                   false, [](AccelKind, const GenOptions& o) {
                     return GroundSphere("huge/ground-sphere-tilted", 1e6, {0.6, 0.8, 0.0}, o);
                   }});
  specs.push_back({"huge/ground-sphere-1e7", "huge",
                   std::string("As ground-sphere-1e6 with the centre 1e7 below (float spacing 1 at the centre).") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) {
                     return GroundSphere("huge/ground-sphere-1e7", 1e7, {0.0, 1.0, 0.0}, o);
                   }});
  specs.push_back({"huge/tilted-triangles", "huge",
                   std::string("Two quads of two triangle statements each, 1e6 and 2e6 across, in tilted planes, one "
                               "through the origin's neighbourhood and one 3e5 away; cameras 10..100 above them and "
                               "beside the shared diagonal, rays at points 1..3000 away and at the diagonal.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return TiltedTriangles(o); }});
  specs.push_back({"huge/cones", "huge",
                   std::string("A cylinder of radius 1e6 - 1 along z as a ground (axis 1e6 below), and a cone 1e6 "
                               "long of radius 1 to 2 seen from 20..100 away.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return HugeCones(o); }});
  specs.push_back({"huge/ground-box", "huge",
                   std::string("A box primitive 2e6 across as a ground (top face y = -1) with a 0.5-unit box on it; "
                               "cameras 10..100 above, rays down at up to 85 degrees and at the small box.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return GroundBox(o); }});
  specs.push_back({"huge/ground-quadric", "huge",
                   std::string("A ground ellipsoid quadric 2e6 x 1e6 x 2e6 (top at y = 0, clipped to y >= -10) with a "
                               "paraboloid bowl and a tilted hyperboloid on it; cameras 10..100 above, rays down at up "
                               "to 85 degrees and at the small quadrics.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return GroundQuadric(o); }});
  specs.push_back({"huge/polyhedra", "huge",
                   std::string("Convex polyhedra (a cube, an octahedron, a slab 0.02 thick and tilted) near the "
                               "origin and the same 1e6 away; rays from 5..50 away at their vertices and edges (some "
                               "a float step off; judged by check's tolerance), at random points near them, and lying in "
                               "the cube's face planes.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return Polyhedra(o); }});
  specs.push_back({"huge/far-origins", "huge",
                   "8 triangles 0.5..3 across, 4 spheres and a cone near the origin; ray origins 1e5..2e6 away in "
                   "the triangles' planes (a third of them off the plane by up to 1e-3 of the distance), directions "
                   "at random and at the triangles: each triangle seen edge-on from far away, where every edge "
                   "function lies below its rounding. Expect: the reference's answer under check.h's tolerance.",
                   false, [](AccelKind, const GenOptions& o) { return FarOrigins(o); }});
  specs.push_back({"huge/tiny-triangles-far", "huge",
                   "60 triangles 1e-3..1e-2 across standing on a ground sphere of radius 1e5; rays from 1e4..1e5 "
                   "away, at random, at the triangles, near them, and at points of their planes 10..3e4 from them "
                   "(where float, its vertices rounded together, can read a hit at the plane's crossing). Expect: "
                   "the reference's answer under check.h's tolerance.",
                   false, [](AccelKind, const GenOptions& o) { return TinyTrianglesFar(o); }});
  specs.push_back({"huge/mixed-scales", "huge",
                   std::string("Spheres of radius 1e-4, triangles 2e-4 across and cylinders of radius 1e-4 standing on a "
                               "ground sphere of radius 1e6, next to a tilted triangle 1e6 across; cameras 0.01..1 "
                               "away, rays aimed at the features.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return Mixed(o); }});
}

}  // namespace cr::hard
