// Grazing: rays tangent to spheres, cylinders and cones, rays lying in a
// cone's or cylinder's surface, and rays in the plane of a triangle or a
// polygon (through its edges and its internal diagonals), all inside a
// backstop box. The tangent and in-plane rays are exact: tangent points are
// integer points of the surface (3-4-5 triangles), directions integer
// vectors orthogonal to the radius (a cross product of integers), planes
// with integer normals; a second share is tangent only up to rounding (a
// random tangent computed in double and rounded), and some are moved by one
// ulp to either side. Expectation: the grazed primitive where the reference
// says it is hit or marginal, else the backstop: never a miss, never NaN.
#include <cmath>

#include "tests/hard/gen/hard_gen.h"

namespace cr::hard {

namespace {

// Integer vectors of length 5.
std::vector<glm::dvec3> Radius5Points()
{
  std::vector<glm::dvec3> out;
  const int base[][3] = {{5, 0, 0}, {3, 4, 0}, {4, 3, 0}};
  for (const auto& b : base)
    for (int perm = 0; perm < 3; ++perm)
      for (int sx = -1; sx <= 1; sx += 2)
        for (int sy = -1; sy <= 1; sy += 2)
          for (int sz = -1; sz <= 1; sz += 2) {
            glm::dvec3 p;
            for (int a = 0; a < 3; ++a) p[(a + perm) % 3] = b[a];
            p *= glm::dvec3(sx, sy, sz);
            out.push_back(p);
          }
  return out;
}

glm::dvec3 SmallInt(Rng& rng, int m)
{
  return {double(int(rng.Below(2 * m + 1)) - m), double(int(rng.Below(2 * m + 1)) - m),
          double(int(rng.Below(2 * m + 1)) - m)};
}

// One float ulp of x towards `towards`.
float Ulp(float x, float towards) { return std::nextafter(x, towards); }

constexpr double kBox = 60.0;

HardCase GrazingCurved(const GenOptions& o)
{
  SceneBuilder b;
  const glm::dvec3 cs(-20.0, 0.5, 0.25);           // sphere, radius 5
  const glm::dvec3 cc(20.0, 0.5, 0.0);             // cylinder along z, radius 5, z in [-10, 10]
  const glm::dvec3 ck(0.0, 30.0, 0.0);             // cone along z, radius 5 at z = -10 to 2 at z = 10
  b.Sphere(cs, 5.0);
  b.Cone(cc - glm::dvec3(0, 0, 10), 5.0, cc + glm::dvec3(0, 0, 10), 5.0);
  b.Cone(ck - glm::dvec3(0, 0, 10), 5.0, ck + glm::dvec3(0, 0, 10), 2.0);
  b.Box(glm::dvec3(-kBox), glm::dvec3(kBox));
  HardCase c;
  c.name = "grazing/curved";
  c.scene = b.Finish();
  c.expect = Expect::Backstopped;
  Rng rng(501);
  const std::vector<glm::dvec3> r5 = Radius5Points();
  const std::size_t count = o.quick ? 3000 : 30000;
  while (c.rays.size() < count) {
    const int family = int(c.rays.size() % 6);
    glm::dvec3 p, d;
    switch (family) {
      case 0: {  // exact sphere tangent
        const glm::dvec3 n = r5[rng.Below(std::uint32_t(r5.size()))];
        d = glm::cross(n, SmallInt(rng, 3));
        p = cs + n;
        break;
      }
      case 1: {  // near tangent: random direction, tangent point in double, rounded
        d = rng.UnitVector();
        glm::dvec3 n = glm::normalize(glm::cross(d, rng.UnitVector()));
        p = cs + 5.0 * n;
        break;
      }
      case 2: {  // exact cylinder tangent, or along the surface
        glm::dvec3 n = r5[rng.Below(std::uint32_t(r5.size()))];
        n.z = 0.0;
        if (n == glm::dvec3(0.0)) n = glm::dvec3(5, 0, 0);
        n *= 5.0 / glm::length(n);  // (3,4,0), (5,0,0), ... (already length 5 in the plane, or rescaled)
        if (!ExactF(n)) n = glm::dvec3(0, -5, 0);
        p = cc + n + glm::dvec3(0, 0, double(int(rng.Below(17)) - 8));
        d = rng.Uniform() < 0.3 ? glm::dvec3(0, 0, rng.Uniform() < 0.5 ? 1 : -1)
                                : glm::dvec3(n.y, -n.x, double(int(rng.Below(7)) - 3));
        break;
      }
      case 3: {  // cone generator lines (in the surface) and tangent lines through them
        const int q = int(rng.Below(4));
        const glm::dvec3 u(q == 0 ? 1 : q == 1 ? -1 : 0, q == 2 ? 1 : q == 3 ? -1 : 0, 0);
        const glm::dvec3 base = ck + 5.0 * u - glm::dvec3(0, 0, 10), apex = ck + 2.0 * u + glm::dvec3(0, 0, 10);
        const double s = double(1 + rng.Below(3)) * 0.25;
        p = base + s * (apex - base);
        d = rng.Uniform() < 0.5 ? apex - base : glm::dvec3(-u.y, u.x, 0) + double(int(rng.Below(5)) - 2) * (apex - base);
        break;
      }
      case 4: {  // exact tangents shifted by one ulp inward or outward
        const glm::dvec3 n = r5[rng.Below(std::uint32_t(r5.size()))];
        d = glm::cross(n, SmallInt(rng, 3));
        glm::vec3 pf(cs + n);
        const int a = std::fabs(n.x) >= std::fabs(n.y) ? (std::fabs(n.x) >= std::fabs(n.z) ? 0 : 2)
                                                       : (std::fabs(n.y) >= std::fabs(n.z) ? 1 : 2);
        pf[a] = Ulp(pf[a], rng.Uniform() < 0.5 ? -INFINITY : INFINITY);
        p = D(pf);
        break;
      }
      default: {  // the cylinder's and cone's rims: tangent to the end circles
        const bool cyl = rng.Uniform() < 0.5;
        const glm::dvec3 centre = (cyl ? cc : ck) + glm::dvec3(0, 0, rng.Uniform() < 0.5 ? -10 : 10);
        const double r = cyl || centre.z < 0 ? 5.0 : 2.0;
        glm::dvec3 n = r5[rng.Below(std::uint32_t(r5.size()))];
        n.z = 0;
        if (n == glm::dvec3(0.0)) n = glm::dvec3(0, 5, 0);
        n *= r / glm::length(n);
        p = centre + n;
        d = glm::dvec3(n.y, -n.x, double(int(rng.Below(5)) - 2));
        break;
      }
    }
    if (d == glm::dvec3(0.0)) continue;
    // Start before the grazing point (or exactly on it, one ray in 8).
    const double s = c.rays.size() % 8 == 0 ? 0.0 : double(1 + rng.Below(4));
    const glm::dvec3 origin = p - s * d;
    if (std::fabs(origin.x) >= kBox || std::fabs(origin.y) >= kBox || std::fabs(origin.z) >= kBox) continue;
    c.rays.push_back(Rec(origin, d));
  }
  return c;
}

HardCase GrazingPlanar(const GenOptions& o)
{
  SceneBuilder b;
  const glm::dvec3 t0(0, 0, 0.75), t1(8, 1, 0.75), t2(3, 7, 0.75);  // in z = 0.75
  b.Triangle(t0, t1, t2);
  // Pentagon in y = -20.5 (three pieces: rays along its diagonals).
  const std::vector<glm::dvec3> pent = {{0, -20.5, 0}, {6, -20.5, 0}, {8, -20.5, 5}, {3, -20.5, 9}, {-2, -20.5, 5}};
  b.Polygon(pent);
  // Tilted triangle in the plane x + 2y + 2z = 30.
  const glm::dvec3 q0(10, 4, 6), q1(0, 5, 10), q2(14, 2, 6);
  b.Triangle(q0, q1, q2);
  b.Box(glm::dvec3(-kBox), glm::dvec3(kBox));
  HardCase c;
  c.name = "grazing/planar";
  c.scene = b.Finish();
  c.expect = Expect::Backstopped;
  Rng rng(502);
  const std::size_t count = o.quick ? 3000 : 30000;
  const glm::dvec3 tilted[] = {{2, -1, 0}, {0, 1, -1}, {2, 0, -1}, {4, -1, -1}, {0, -1, 1}, {-2, 2, -1}};
  while (c.rays.size() < count) {
    const int family = int(c.rays.size() % 5);
    glm::dvec3 p, d;
    switch (family) {
      case 0: {  // in the plane z = 0.75, anywhere across the triangle, d.z = +-0
        p = glm::dvec3(rng.Uniform(-2, 10), rng.Uniform(-2, 9), 0.75);
        d = glm::dvec3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform() < 0.5 ? 0.0 : -0.0);
        break;
      }
      case 1: {  // along the triangle's edges and through its vertices, in its plane
        const glm::dvec3 v[3] = {t0, t1, t2};
        const int e = int(rng.Below(3));
        p = v[e];
        d = rng.Uniform() < 0.5 ? v[(e + 1) % 3] - v[e]
                                : glm::dvec3(double(int(rng.Below(9)) - 4), double(int(rng.Below(9)) - 4), 0);
        break;
      }
      case 2: {  // in the pentagon's plane: between vertices (edges and diagonals) and random
        const glm::dvec3 a = pent[rng.Below(5)], bb = pent[rng.Below(5)];
        p = a;
        d = rng.Uniform() < 0.6 ? bb - a : glm::dvec3(rng.Uniform(-1, 1), 0.0, rng.Uniform(-1, 1));
        break;
      }
      case 3: {  // in the tilted plane, exactly (integer points, directions with d.n = 0)
        const glm::dvec3 v[3] = {q0, q1, q2};
        p = v[rng.Below(3)];
        d = tilted[rng.Below(6)] * double(1 + rng.Below(3));
        if (rng.Uniform() < 0.5) d = -d;
        break;
      }
      default: {  // one ulp off the plane z = 0.75, either side
        glm::vec3 pf(float(rng.Uniform(-2, 10)), float(rng.Uniform(-2, 9)), 0.75f);
        pf.z = Ulp(pf.z, rng.Uniform() < 0.5 ? -INFINITY : INFINITY);
        p = D(pf);
        d = glm::dvec3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), 0.0);
        break;
      }
    }
    if (d == glm::dvec3(0.0)) continue;
    const double s = c.rays.size() % 8 == 0 ? 0.0 : double(1 + rng.Below(3));
    glm::dvec3 origin = p - s * d;
    if (family == 0 || family == 4) origin = p - s * glm::dvec3(glm::vec3(d));  // d is rounded: stay in the plane
    if (std::fabs(origin.x) >= kBox || std::fabs(origin.y) >= kBox || std::fabs(origin.z) >= kBox) continue;
    c.rays.push_back(Rec(origin, d));
  }
  return c;
}

}  // namespace

void AddGrazingCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"grazing/curved", "grazing",
                   "A sphere, a cylinder and a cone (radius 5, integer tangent points) in a backstop box: exact "
                   "tangents (integer directions orthogonal to the radius), tangents rounded from double, tangents "
                   "moved one ulp in or out, rays lying in the cylinder's and the cone's surface, tangents to their "
                   "rims; origins before the tangent point or on it. Expect: the grazed surface if the reference "
                   "hits it or it is marginal, else the backstop; never a miss, never NaN.",
                   false, [](AccelKind, const GenOptions& o) { return GrazingCurved(o); }});
  specs.push_back({"grazing/planar", "grazing",
                   "A triangle in z = 0.75, a pentagon (three pieces) in y = -20.5, a triangle in x + 2y + 2z = 30, "
                   "in a backstop box: rays in their planes (d component +-0, or integer directions in the tilted "
                   "plane), along their edges and diagonals, and one ulp off the plane. Expect as grazing/curved.",
                   false, [](AccelKind, const GenOptions& o) { return GrazingPlanar(o); }});
}

}  // namespace cr::hard
