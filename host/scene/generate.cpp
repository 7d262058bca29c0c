#include "host/scene/generate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/scene/nff.h"

namespace cr {

namespace {

constexpr double kPi = 3.14159265358979323846;

void AddSphere(Scene& s, const glm::dvec3& c, double r, std::uint32_t material)
{
  PrimInfo info;
  info.type = CR_PRIM_SPHERE;
  info.material = material;
  info.nPieces = 1;
  info.firstPiece = s.AddPiece(Sphere{{float(c.x), float(c.y), float(c.z)}, float(r)}, s.NumPrims());
  s.prims.push_back(info);
}

void AddTriangle(Scene& s, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, std::uint32_t material)
{
  PrimInfo info;
  info.kind = PrimKind::kPolygon;
  info.type = CR_PRIM_TRIANGLE;
  info.material = material;
  info.nPieces = 1;
  Triangle t{};
  for (int k = 0; k < 3; ++k) {
    t.v0[k] = float(a[k]);
    t.v1[k] = float(b[k]);
    t.v2[k] = float(c[k]);
  }
  t.flags = CR_TRI_REPORT_UV | TriangleEdgeFlags(t);
  info.firstPiece = s.AddPiece(t, s.NumPrims());
  s.prims.push_back(info);
}

// A quad as two triangle primitives (WriteNFF writes triangles only).
void AddQuad(Scene& s, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d,
             std::uint32_t material)
{
  AddTriangle(s, a, b, c, material);
  AddTriangle(s, a, c, d, material);
}

Scene Base(const glm::vec3& from, const glm::vec3& at, float angle)
{
  Scene s;
  s.path = "generated";
  s.background = glm::vec3(0.078f, 0.361f, 0.753f);
  s.camera.from = from;
  s.camera.at = at;
  s.camera.up = glm::vec3(0.0f, 0.0f, 1.0f);
  s.camera.angle = angle;
  s.camera.hither = 0.01f;
  s.hasCamera = true;
  s.materials.push_back(Material{});
  return s;
}

// balls.c's recursion: children at 6 equatorial and 3 upper directions,
// rotated into the frame of the parent's direction.
void Flake(Scene& s, const glm::dvec3& c, double r, const glm::dvec3& dir, int depth, std::uint32_t mat)
{
  AddSphere(s, c, r, mat);
  if (depth == 0) return;
  glm::dvec3 a = std::fabs(dir.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  glm::dvec3 u = glm::normalize(glm::cross(dir, a)), v = glm::cross(dir, u);
  const double rc = r / 3.0;
  for (int i = 0; i < 9; ++i) {
    double elev = i < 6 ? 0.0 : 0.9 * kPi / 4.0 * 1.2;  // upper ring tilted toward dir
    double az = i < 6 ? i * kPi / 3.0 : (i - 6) * 2.0 * kPi / 3.0 + kPi / 6.0;
    glm::dvec3 d = std::cos(elev) * (std::cos(az) * u + std::sin(az) * v) + std::sin(elev) * dir;
    d = glm::normalize(d);
    Flake(s, c + d * (r + rc), rc, d, depth - 1, mat);
  }
}

}  // namespace

Scene GenerateSphereflake(int depth)
{
  if (depth < 0 || depth > 8) throw InputError(fmt::format("sphereflake depth {} is not in 0..8", depth));
  Scene s = Base({2.1f, 1.3f, 1.7f}, {0.0f, 0.0f, 0.0f}, 45.0f);
  s.lights = {Light{{4, 3, 2}, glm::vec3(1)}, Light{{1, -4, 4}, glm::vec3(1)}, Light{{-3, 1, 5}, glm::vec3(1)}};
  s.materials.push_back(Material{{1.0f, 0.75f, 0.33f}, 0.8f, 0.0f, 100000.0f, 0.0f, 1.0f});
  s.materials.push_back(Material{{1.0f, 0.9f, 0.7f}, 0.5f, 0.5f, 3.0827f, 0.0f, 1.0f});
  AddQuad(s, {12, 12, -0.5}, {-12, 12, -0.5}, {-12, -12, -0.5}, {12, -12, -0.5}, 1);
  Flake(s, {0, 0, 0}, 0.5, {0, 0, 1}, depth, 2);
  return s;
}

Scene GenerateBumpySphere(std::uint64_t triangles)
{
  if (triangles < 12 || triangles > (std::uint64_t(1) << 27))
    throw InputError(fmt::format("mesh of {} triangles: expected 12 .. 2^27", triangles));
  const int n = std::max(1, int(std::lround(std::sqrt(double(triangles) / 12.0))));
  Scene s = Base({0.0f, -4.2f, 2.0f}, {0.0f, 0.0f, 0.0f}, 40.0f);
  s.lights = {Light{{5, -6, 8}, glm::vec3(1)}, Light{{-7, -3, 2}, glm::vec3(1)}};
  s.materials.push_back(Material{{0.8f, 0.8f, 0.85f}, 0.8f, 0.2f, 20.0f, 0.0f, 1.0f});
  auto point = [&](int face, int i, int j) {
    double a = 2.0 * i / n - 1.0, b = 2.0 * j / n - 1.0;
    glm::dvec3 p;
    switch (face) {
      case 0: p = {1, a, b}; break;
      case 1: p = {-1, b, a}; break;
      case 2: p = {b, 1, a}; break;
      case 3: p = {a, -1, b}; break;
      case 4: p = {a, b, 1}; break;
      default: p = {b, a, -1}; break;
    }
    p = glm::normalize(p);
    double bump = 1.0 + 0.04 * std::sin(9.0 * p.x) * std::sin(11.0 * p.y) * std::sin(7.0 * p.z) +
                  0.01 * std::sin(40.0 * p.x + 3.0 * p.z);
    return p * bump;
  };
  s.prims.reserve(std::size_t(12) * n * n);
  for (int f = 0; f < 6; ++f)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        glm::dvec3 p00 = point(f, i, j), p10 = point(f, i + 1, j), p01 = point(f, i, j + 1), p11 = point(f, i + 1, j + 1);
        AddTriangle(s, p00, p10, p11, 1);
        AddTriangle(s, p00, p11, p01, 1);
      }
  return s;
}

Scene SubdivideMesh(const Scene& mesh, std::uint64_t triangles)
{
  const std::uint64_t n0 = mesh.triangles.size();
  const bool onlyTriangles = std::all_of(mesh.prims.begin(), mesh.prims.end(), [](const PrimInfo& p) {
    return p.type == CR_PRIM_TRIANGLE && p.part == 0 && p.motion == glm::vec3(0.0f);
  });
  if (n0 == 0 || !onlyTriangles)
    throw InputError(fmt::format("{}: subdivision needs a static mesh of triangles only", mesh.path));
  if (triangles < n0 || triangles > (std::uint64_t(1) << 27))
    throw InputError(fmt::format("{}: subdivision to {} triangles: expected {} .. 2^27", mesh.path, triangles, n0));
  struct Tri {
    glm::dvec3 v[3];
    std::uint32_t material;
  };
  std::vector<Tri> tris;
  tris.reserve(std::size_t(triangles));
  for (std::uint32_t g = 0; g < n0; ++g) {
    const Triangle& t = mesh.triangles[g];
    Tri x{};
    for (int k = 0; k < 3; ++k) x.v[0][k] = t.v0[k], x.v[1][k] = t.v1[k], x.v[2][k] = t.v2[k];
    x.material = mesh.prims[mesh.pieceIds[CR_PRIM_TRIANGLE][g]].material;
    tris.push_back(x);
  }
  // Midpoints as (a + b) / 2 in double: the same point from either side.
  const auto mid = [](const glm::dvec3& a, const glm::dvec3& b) { return 0.5 * (a + b); };
  while (tris.size() * 4 <= triangles) {
    std::vector<Tri> next;
    next.reserve(tris.size() * 4);
    for (const Tri& t : tris) {
      const glm::dvec3 m01 = mid(t.v[0], t.v[1]), m12 = mid(t.v[1], t.v[2]), m20 = mid(t.v[2], t.v[0]);
      next.push_back({{t.v[0], m01, m20}, t.material});
      next.push_back({{m01, t.v[1], m12}, t.material});
      next.push_back({{m20, m12, t.v[2]}, t.material});
      next.push_back({{m01, m12, m20}, t.material});
    }
    tris.swap(next);
  }
  // Bisections of the largest triangles, round by round, up to the target.
  while (tris.size() < triangles) {
    const std::size_t split = std::min<std::size_t>(tris.size(), std::size_t(triangles) - tris.size());
    const auto area = [](const Tri& t) { return glm::length(glm::cross(t.v[1] - t.v[0], t.v[2] - t.v[0])); };
    std::vector<std::size_t> order(tris.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    if (split < tris.size())
      std::nth_element(order.begin(), order.begin() + std::ptrdiff_t(split), order.end(),
                       [&](std::size_t a, std::size_t b) { return area(tris[a]) > area(tris[b]); });
    tris.reserve(tris.size() + split);  // no reallocation below: t stays valid
    for (std::size_t k = 0; k < split; ++k) {
      Tri& t = tris[order[k]];
      int e = 0;  // the longest edge: v[e] to v[(e + 1) % 3]
      double best = -1.0;
      for (int i = 0; i < 3; ++i) {
        const double l = glm::length(t.v[(i + 1) % 3] - t.v[i]);
        if (l > best) best = l, e = i;
      }
      const glm::dvec3 a = t.v[e], b = t.v[(e + 1) % 3], c = t.v[(e + 2) % 3], m = mid(a, b);
      tris.push_back({{m, b, c}, t.material});
      t = {{a, m, c}, t.material};
    }
  }
  Scene s;
  s.path = mesh.path;
  s.camera = mesh.camera;
  s.hasCamera = mesh.hasCamera;
  s.background = mesh.background;
  s.lights = mesh.lights;
  s.materials = mesh.materials;
  s.prims.reserve(tris.size());
  s.triangles.reserve(tris.size());
  for (const Tri& t : tris) AddTriangle(s, t.v[0], t.v[1], t.v[2], t.material);
  return s;
}

Scene GenerateStadium(int depth)
{
  if (depth < 0 || depth > 6) throw InputError(fmt::format("stadium object depth {} is not in 0..6", depth));
  Scene s = Base({1.2f, -1.6f, 0.9f}, {0.0f, 0.0f, 0.1f}, 40.0f);
  s.lights = {Light{{3000, -2000, 4000}, glm::vec3(1)}, Light{{-2, -3, 4}, glm::vec3(1)}};
  s.materials.push_back(Material{{0.4f, 0.7f, 0.3f}, 0.9f, 0.0f, 1.0f, 0.0f, 1.0f});
  s.materials.push_back(Material{{0.9f, 0.9f, 0.9f}, 0.7f, 0.3f, 30.0f, 0.0f, 1.0f});
  const double half = 5000.0;
  AddQuad(s, {half, half, -0.5}, {-half, half, -0.5}, {-half, -half, -0.5}, {half, -half, -0.5}, 1);
  // A ring of 64 pillars (thin boxes) along the stadium's edge.
  for (int k = 0; k < 64; ++k) {
    double a = 2.0 * kPi * k / 64.0, R = 0.9 * half;
    glm::dvec3 c(R * std::cos(a), R * std::sin(a), 0.0);
    glm::dvec3 e1(20, 0, 0), e2(0, 20, 0), up(0, 0, 400);
    glm::dvec3 lo = c - e1 - e2 + glm::dvec3(0, 0, -0.5);
    glm::dvec3 p[8] = {lo, lo + 2.0 * e1, lo + 2.0 * e1 + 2.0 * e2, lo + 2.0 * e2};
    for (int i = 0; i < 4; ++i) p[i + 4] = p[i] + up;
    const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    for (const auto& f : faces) AddQuad(s, p[f[0]], p[f[1]], p[f[2]], p[f[3]], 2);
  }
  Flake(s, {0, 0, 0}, 0.25, {0, 0, 1}, depth, 2);
  return s;
}

void WriteNFF(const Scene& s, const std::string& path)
{
  WriteAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f) throw RuntimeError(fmt::format("{}: cannot write", path));
    const Camera& c = s.camera;
    fmt::print(f, "b {} {} {}\n", s.background.x, s.background.y, s.background.z);
    fmt::print(f, "v\nfrom {} {} {}\nat {} {} {}\nup {} {} {}\nangle {}\nhither {}\nresolution {} {}\n", c.from.x,
               c.from.y, c.from.z, c.at.x, c.at.y, c.at.z, c.up.x, c.up.y, c.up.z, c.angle, c.hither, c.width,
               c.height);
    for (const Light& l : s.lights)
      fmt::print(f, "l {} {} {} {} {} {}\n", l.position.x, l.position.y, l.position.z, l.color.x, l.color.y, l.color.z);
    std::uint32_t current = ~0u;
    for (const PrimInfo& p : s.prims) {
      if (p.material != current && p.material < s.materials.size()) {
        const Material& m = s.materials[p.material];
        fmt::print(f, "f {} {} {} {} {} {} {} {}\n", m.color.x, m.color.y, m.color.z, m.kd, m.ks, m.shine,
                   m.transmittance, m.ior);
        current = p.material;
      }
      if (p.kind == PrimKind::kShape && p.type == CR_PRIM_SPHERE && p.nPieces) {
        const Sphere& sp = s.spheres[p.firstPiece];
        fmt::print(f, "s {} {} {} {}\n", sp.center[0], sp.center[1], sp.center[2], sp.radius);
      } else if (p.kind == PrimKind::kPolygon && p.nPieces == 1) {
        const Triangle& t = s.triangles[p.firstPiece];
        fmt::print(f, "p 3\n{} {} {}\n{} {} {}\n{} {} {}\n", t.v0[0], t.v0[1], t.v0[2], t.v1[0], t.v1[1], t.v1[2],
                   t.v2[0], t.v2[1], t.v2[2]);
      } else {
        throw RuntimeError("WriteNFF: only generated scenes (spheres and triangles) can be written");
      }
    }
    if (std::fclose(f) != 0) throw RuntimeError(fmt::format("{}: write failed", path));
  });
}

// The frame of the generated fields (quadrics, polyhedra): a ground quad
// 2 half across, the camera above one corner looking across, two lights,
// the ground's material (1) and two shape materials (2, 3).
static Scene FieldBase(double half)
{
  Scene s = Base({float(-0.9 * half), float(-1.1 * half), float(0.25 * half + 3.0)}, {0.0f, 0.0f, 0.0f}, 45.0f);
  s.lights = {Light{{float(-2 * half), float(-half), float(3 * half)}, glm::vec3(1)},
              Light{{float(half), float(-2 * half), float(half)}, glm::vec3(0.6f)}};
  s.materials.push_back(Material{{0.6f, 0.6f, 0.55f}, 0.8f, 0.0f, 10.0f, 0.0f, 1.0f});
  s.materials.push_back(Material{{0.8f, 0.4f, 0.3f}, 0.7f, 0.3f, 30.0f, 0.0f, 1.0f});
  s.materials.push_back(Material{{0.3f, 0.6f, 0.8f}, 0.7f, 0.3f, 30.0f, 0.0f, 1.0f});
  AddQuad(s, {half, half, 0.0}, {-half, half, 0.0}, {-half, -half, 0.0}, {half, -half, 0.0}, 1);
  return s;
}

// Rotation by ax about x, then by az about z (a shape tilted off its axis).
static glm::dmat3 Tilt(double ax, double az)
{
  const glm::dmat3 rx(1, 0, 0, 0, std::cos(ax), std::sin(ax), 0, -std::sin(ax), std::cos(ax));
  const glm::dmat3 rz(std::cos(az), std::sin(az), 0, -std::sin(az), std::cos(az), 0, 0, 0, 1);
  return rz * rx;
}

// A uniform number in [lo, hi) from splitmix64 state.
static double SplitMix(std::uint64_t& state, double lo, double hi)
{
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return lo + (hi - lo) * double(z >> 11) * 0x1.0p-53;
}

Scene GenerateQuadricField(std::uint64_t n)
{
  if (n < 1 || n > (std::uint64_t(1) << 24))
    throw InputError(fmt::format("quadric field of {} quadrics: expected 1 .. 2^24", n));
  const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
  const double half = side;  // cells 2 units across
  Scene s = FieldBase(half);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uni = [&](double lo, double hi) { return SplitMix(state, lo, hi); };
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const glm::dvec3 c(-half + 2.0 * i + 1.0, -half + 2.0 * j + 1.0, uni(0.7, 0.9));
      // the family in its own frame: diag(m) x^2 + b . x + k = 0 (z its axis)
      const int fam = int(uni(0.0, 6.0));
      const double r = uni(0.3, 0.6), h = uni(0.5, 0.8);
      glm::dvec3 m(1.0), b(0.0), ext(0.85);
      double k = -r * r;
      switch (fam) {
        case 0: m = {1.0, uni(0.8, 2.0), uni(1.0, 3.0)}; break;         // ellipsoid
        case 1: m = {1.0, 1.0, -0.25}; k = -r * r * 0.25; break;         // hyperboloid, one sheet
        case 2: m = {-1.0, -1.0, 1.0}; k = -0.05; break;                 // two sheets
        case 3: m = {1.0, 1.0, 0.0}; b = {0, 0, -2.0 * h}; k = 0.0; break;  // paraboloid
        case 4: m = {1.0, 1.0, 0.0}; break;                                  // cylinder
        default: m = {1.0, 1.0, -0.2}; k = 0.0; break;                       // cone
      }
      ext.z = fam == 3 ? 0.5 * h : 0.7;
      // random rotation about x then z
      const double ax = uni(-0.5, 0.5), az = uni(0.0, 2.0 * kPi);
      const glm::dmat3 R = Tilt(ax, az);
      const glm::dmat3 Q = R * glm::dmat3(m.x, 0, 0, 0, m.y, 0, 0, 0, m.z) * glm::transpose(R);
      const glm::dvec3 rb = R * b, qc = Q * c;
      const glm::dvec3 L = rb - 2.0 * qc;
      const double J = glm::dot(c, qc) - glm::dot(rb, c) + k;
      // the clip box: the rotated frame box's axis-aligned bounds, within the cell
      glm::dvec3 e(0.0);
      for (int a = 0; a < 3; ++a)
        for (int q = 0; q < 3; ++q) e[a] += std::fabs(R[q][a]) * ext[q];
      e = glm::min(e, glm::dvec3(0.95, 0.95, c.z));
      NffValues st("quadric", s.path, long(s.NumPrims()),
                   {Q[0][0], Q[1][1], Q[2][2], 2 * Q[1][0], 2 * Q[2][0], 2 * Q[2][1], L.x, L.y, L.z, J, c.x - e.x,
                    c.y - e.y, c.z - e.z, c.x + e.x, c.y + e.y, c.z + e.z},
                   2 + std::uint32_t(fam % 2));
      ReadGeometry(st, s);
    }
  return s;
}

// Crystal face normals in their own frame, each with its support distance
// (n . x <= h), by kind: cube, octahedron, truncated octahedron, a
// hexagonal prism with pyramid caps.
static std::vector<std::pair<glm::dvec3, double>> CrystalFaces(int kind)
{
  std::vector<std::pair<glm::dvec3, double>> f;
  const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (kind == 0 || kind == 2)
    for (const glm::dvec3& a : axes) {
      f.push_back({a, 0.5});
      f.push_back({-a, 0.5});
    }
  if (kind == 1 || kind == 2)
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 n(k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1);
      f.push_back({glm::normalize(n), kind == 1 ? 0.5 : 0.75});
    }
  if (kind == 3) {
    const double m = 0.5 / 0.35;  // caps 0.35 high on a prism 0.5 from its axis, 0.45 half-height
    for (int k = 0; k < 6; ++k) {
      const double a = kPi * k / 3.0;
      f.push_back({{std::cos(a), std::sin(a), 0.0}, 0.5});
      for (double sgn : {1.0, -1.0})
        f.push_back({glm::normalize(glm::dvec3(std::cos(a), std::sin(a), sgn * m)),
                     m * (0.45 + 0.35) / std::sqrt(1.0 + m * m)});
    }
  }
  return f;
}

Scene GeneratePolyhedronField(std::uint64_t n)
{
  if (n < 1 || n > (std::uint64_t(1) << 24))
    throw InputError(fmt::format("polyhedron field of {} polyhedra: expected 1 .. 2^24", n));
  const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
  const double half = side;  // cells 2 units across
  Scene s = FieldBase(half);
  std::uint64_t state = 0x5851F42D4C957F2Dull;
  auto uni = [&](double lo, double hi) { return SplitMix(state, lo, hi); };
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const int kind = int(uni(0.0, 4.0));
      const double scale = uni(0.9, 1.4);
      const glm::dvec3 c(-half + 2.0 * i + 1.0, -half + 2.0 * j + 1.0, 0.5 * scale);
      const double ax = uni(-0.6, 0.6), az = uni(0.0, 2.0 * kPi);
      const glm::dmat3 R = Tilt(ax, az);
      const auto faces = CrystalFaces(kind);
      std::vector<double> v = {double(faces.size())};
      for (const auto& [n0, h] : faces) {
        const glm::dvec3 nn = R * n0;
        v.insert(v.end(), {nn.x, nn.y, nn.z, -(glm::dot(nn, c) + h * scale)});
      }
      NffValues st("polyhedron", s.path, long(s.NumPrims()), std::move(v), 2 + std::uint32_t(kind % 2));
      ReadGeometry(st, s);
    }
  return s;
}

Scene GenerateSdfField(std::uint64_t n)
{
  if (n < 1 || n > (std::uint64_t(1) << 24))
    throw InputError(fmt::format("SDF field of {} blocks: expected 1 .. 2^24", n));
  const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
  const double half = side;  // cells 2 units across
  Scene s = FieldBase(half);
  std::uint64_t state = 0x2545F4914F6CDD1Dull;
  auto uni = [&](double lo, double hi) { return SplitMix(state, lo, hi); };
  std::string text = "f 0.8 0.45 0.3 0.7 0.3 30 0 1\n";
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const double x = -half + 2.0 * i + 1.0, y = -half + 2.0 * j + 1.0;
      const double r = uni(0.3, 0.45), r2 = uni(0.2, 0.35);
      text += fmt::format("sdf {} {} 0 {} {} 1.6 0.001 256 1.5\n", x - 0.95, y - 0.95, x + 0.95, y + 0.95);
      text += fmt::format("sphere {} {} {} {}\n", x + uni(-0.3, 0.3), y + uni(-0.3, 0.3), r, r);
      text += fmt::format("sphere {} {} {} {}\nsmooth 0.25\n", x + uni(-0.3, 0.3), y + uni(-0.3, 0.3),
                          r + uni(0.3, 0.6), r2);
      switch (int(uni(0.0, 3.0))) {
        case 0: text += fmt::format("torus {} {} 0.6 0.45 0.08\nunion\n", x, y); break;
        case 1:
          text += fmt::format("capsule {} {} 0.2 {} {} 0.9 0.1\nunion\n", x - 0.6, y, x + 0.6, y + uni(-0.3, 0.3));
          break;
        default: text += fmt::format("roundbox {} {} 0.12 0.6 0.6 0.12 0.05\nunion\n", x, y); break;
      }
      text += "sdf end\n";
    }
  ParseNFF(text, s.path, s);
  return s;
}

Scene GenerateCsgField(std::uint64_t n)
{
  if (n < 1 || n > (std::uint64_t(1) << 22))
    throw InputError(fmt::format("CSG field of {} solids: expected 1 .. 2^22", n));
  const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
  const double half = side;  // cells 2 units across
  Scene s = FieldBase(half);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uni = [&](double lo, double hi) { return SplitMix(state, lo, hi); };
  std::string text;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const double x = -half + 2.0 * i + 1.0, y = -half + 2.0 * j + 1.0;
      const double h = uni(0.45, 0.65), z = h + 0.05;
      text += fmt::format("f {} {} {} 0.7 0.3 30 0 1\n", uni(0.4, 0.95), uni(0.4, 0.95), uni(0.4, 0.95));
      switch (int(uni(0.0, 3.0))) {
        case 0:  // a rounded cube with three bites
          text += fmt::format("csg difference\ncsg intersection\nbox {} {} {} {} {} {}\ns {} {} {} {}\ncsg end\n", x - h,
                              y - h, z - h, x + h, y + h, z + h, x, y, z, 1.4 * h);
          for (int k = 0; k < 3; ++k)
            text += fmt::format("s {} {} {} {}\n", x + uni(-h, h), y + uni(-h, h), z + h, uni(0.15, 0.3) * h);
          text += "csg end\n";
          break;
        case 1:  // a lens with a notch
          text += fmt::format("csg difference\ncsg intersection\ns {} {} {} {}\ns {} {} {} {}\ncsg end\n", x, y - 0.5 * h,
                              z, 1.1 * h, x, y + 0.5 * h, z, 1.1 * h);
          text += fmt::format("box {} {} {} {} {} {}\ncsg end\n", x - 0.2 * h, y - h, z, x + 0.2 * h, y + h, z + h);
          break;
        default:  // three bars with a spherical bite
          text += fmt::format("csg difference\ncsg union\nbox {} {} {} {} {} {}\nbox {} {} {} {} {} {}\n", x - h,
                              y - 0.2 * h, z - 0.2 * h, x + h, y + 0.2 * h, z + 0.2 * h, x - 0.2 * h, y - h, z - 0.2 * h,
                              x + 0.2 * h, y + h, z + 0.2 * h);
          text += fmt::format("box {} {} {} {} {} {}\ncsg end\ns {} {} {} {}\ncsg end\n", x - 0.2 * h, y - 0.2 * h,
                              z - h, x + 0.2 * h, y + 0.2 * h, z + h, x + 0.5 * h, y + 0.5 * h, z + 0.5 * h, 0.6 * h);
          break;
      }
    }
  ParseNFF(text, s.path, s);
  return s;
}

}  // namespace cr
