// Leaks: rays from inside closed, watertight triangle meshes, many of them
// passing exactly through a vertex or a point of an edge, must all hit, at
// the first crossing (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
// Intersection": shared edges and vertices must not let a ray through).
//
// Exactness: mesh vertices are snapped to multiples of 2^-16 (the meshes
// span [-2, 2]), so sums of a few vertices with small integer weights are
// exact in float. A ray from lattice point o with direction
//   d = (2^m - k) a + k b - 2^m o
// passes exactly through the edge point a + (b - a) k / 2^m at t = 2^-m,
// and d = v - o exactly through vertex v at t = 1: the float ray the tracer
// gets is the ray the case means.
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"
#include "host/core/error.h"

namespace cr::hard {

namespace {

constexpr double kStep = 0x1p-16;

struct Mesh {
  std::vector<glm::dvec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  std::vector<std::uint32_t> special;  // vertices shared by very many triangles (fan centres)
};

// Every undirected edge in exactly two triangles, no repeated vertex.
void CheckClosed(const Mesh& m, const char* name)
{
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& t : m.t)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a == b) throw RuntimeError(fmt::format("hard case {}: repeated vertex", name));
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [e, n] : edges)
    if (n != 2) throw RuntimeError(fmt::format("hard case {}: mesh not closed (edge in {} triangles)", name, n));
  std::map<std::array<double, 3>, int> seen;
  for (const auto& p : m.v)
    if (seen[{p.x, p.y, p.z}]++) throw RuntimeError(fmt::format("hard case {}: two vertices snapped together", name));
}

Mesh Icosphere(int levels)
{
  Mesh m;
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                               {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<std::array<std::uint32_t, 3>> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return mid[key] = std::uint32_t(v.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    next.reserve(t.size() * 4);
    for (const auto& f : t) {
      const std::uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    t.swap(next);
  }
  for (auto& p : v) p = Snap(p, kStep);
  m.v = std::move(v);
  m.t = std::move(t);
  return m;
}

// The cube [-1, 1]^3, each face an n x n grid of quads split along
// alternating diagonals; vertices shared across faces and cube edges.
Mesh SplitCube(int n)
{
  Mesh m;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vert = [&](std::array<int, 3> k) {
    auto it = index.find(k);
    if (it != index.end()) return it->second;
    m.v.push_back(Snap(glm::dvec3(k[0], k[1], k[2]) * (2.0 / n) - 1.0, kStep));
    return index[k] = std::uint32_t(m.v.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= 1; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::array<int, 3> k00{}, k10{}, k11{}, k01{};
          for (auto* k : {&k00, &k10, &k11, &k01}) (*k)[axis] = side * n;
          k00[u] = i, k00[w] = j;
          k10[u] = i + 1, k10[w] = j;
          k11[u] = i + 1, k11[w] = j + 1;
          k01[u] = i, k01[w] = j + 1;
          const std::uint32_t a = vert(k00), b = vert(k10), c = vert(k11), d = vert(k01);
          if ((i + j) % 2 == 0) {
            m.t.push_back({a, b, c});
            m.t.push_back({a, c, d});
          } else {
            m.t.push_back({a, b, d});
            m.t.push_back({b, c, d});
          }
        }
    }
  return m;
}

// A closed cone: apex (0, 0, 2) over a base circle of radius 1 in z = 0 with
// n rim vertices; the base is a fan around its centre. Apex and base centre
// are each shared by n triangles.
Mesh FanCone(int n)
{
  Mesh m;
  m.v.push_back({0, 0, 2});  // 0: apex
  m.v.push_back({0, 0, 0});  // 1: base centre
  m.special = {0, 1};
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    m.v.push_back(Snap(glm::dvec3(std::cos(a), std::sin(a), 0.0), kStep));
  }
  for (int i = 0; i < n; ++i) {
    const std::uint32_t r0 = 2 + i, r1 = 2 + (i + 1) % n;
    m.t.push_back({r0, r1, 0});
    m.t.push_back({r1, r0, 1});
  }
  return m;
}

using Inside = bool (*)(const glm::dvec3&);

bool InIcosphere(const glm::dvec3& p) { return glm::length(p) < 0.9; }
bool InCube(const glm::dvec3& p) { return std::fabs(p.x) < 0.95 && std::fabs(p.y) < 0.95 && std::fabs(p.z) < 0.95; }
bool InCone(const glm::dvec3& p)
{
  return p.z > 0.02 && p.z < 1.9 && std::hypot(p.x, p.y) < 0.95 * (1.0 - p.z / 2.0);
}

glm::dvec3 InsidePoint(Rng& rng, Inside inside)
{
  for (;;) {
    const glm::dvec3 p = Snap(rng.InBox(glm::dvec3(-1), glm::dvec3(1, 1, 2)), kStep);
    if (inside(p)) return p;
  }
}

// `count` rays from inside: 40% through a vertex, 40% through an edge point,
// 10% through a face centroid, 10% in random directions; for meshes with fan
// centres a third of the vertex rays aim at those, half of them from the
// axis (axis-parallel directions).
std::vector<RayRecord> LeakRays(const Mesh& m, Inside inside, std::size_t count, std::uint64_t seed)
{
  Rng rng(seed);
  std::vector<RayRecord> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const glm::dvec3 axisPoint(0.0, 0.0, 0.5);
    glm::dvec3 o = rays.size() % 10 == 0 && inside(axisPoint) ? axisPoint : InsidePoint(rng, inside);
    const double kind = rng.Uniform();
    glm::dvec3 d;
    if (kind < 0.4) {
      std::uint32_t vi = rng.Below(std::uint32_t(m.v.size()));
      if (!m.special.empty() && rng.Uniform() < 0.33) {
        vi = m.special[rng.Below(std::uint32_t(m.special.size()))];
        if (rng.Uniform() < 0.5) o = Snap(glm::dvec3(0.0, 0.0, rng.Uniform(0.05, 1.8)), kStep);
      }
      d = m.v[vi] - o;
    } else if (kind < 0.8) {
      const auto& f = m.t[rng.Below(std::uint32_t(m.t.size()))];
      const int e = int(rng.Below(3));
      const glm::dvec3 a = m.v[f[e]], b = m.v[f[(e + 1) % 3]];
      const int mExp = 1 + int(rng.Below(4));
      const double s = std::ldexp(1.0, mExp);
      const double k = 1.0 + double(rng.Below(std::uint32_t(s) - 1));
      d = (s - k) * a + k * b - s * o;
    } else if (kind < 0.9) {
      const auto& f = m.t[rng.Below(std::uint32_t(m.t.size()))];
      d = m.v[f[0]] + m.v[f[1]] + m.v[f[2]] - 3.0 * o;
    } else {
      d = rng.UnitVector();
    }
    if (kind < 0.9 && !ExactF(d)) continue;  // not exact: draw again (does not happen on the lattice)
    if (d == glm::dvec3(0.0)) continue;
    rays.push_back(Rec(o, d));
  }
  return rays;
}

HardCase LeakCase(const char* name, const Mesh& m, Inside inside, std::size_t count, std::uint64_t seed)
{
  CheckClosed(m, name);
  SceneBuilder b;
  for (const auto& t : m.t) b.Triangle(m.v[t[0]], m.v[t[1]], m.v[t[2]]);
  HardCase c;
  c.name = name;
  c.scene = b.Finish();
  if (c.scene->triangles.size() != m.t.size())
    throw RuntimeError(fmt::format("hard case {}: a triangle was dropped as degenerate", name));
  c.rays = LeakRays(m, inside, count, seed);
  c.expect = Expect::Closed;
  return c;
}

// A room [-1,1]^3 walled by six box primitives 0.25 thick that overlap at
// its edges and corners. Rays from inside (origins on a 2^-8 lattice) aimed
// exactly at the room's corners (40%), at points of its edges (40%) and of
// its faces (20%): where two or three walls meet, a ray must hit one of
// them at the room's surface.
HardCase BoxRoom(const GenOptions& o)
{
  SceneBuilder b;
  const double e = 1.25;
  b.AxisBox({-e, -e, -e}, {e, -1.0, e});
  b.AxisBox({-e, 1.0, -e}, {e, e, e});
  b.AxisBox({-e, -1.0, -e}, {-1.0, 1.0, e});
  b.AxisBox({1.0, -1.0, -e}, {e, 1.0, e});
  b.AxisBox({-1.0, -1.0, -e}, {1.0, 1.0, -1.0});
  b.AxisBox({-1.0, -1.0, 1.0}, {1.0, 1.0, e});
  HardCase c;
  c.name = "leaks/box-room";
  c.scene = b.Finish();
  c.expect = Expect::Closed;
  // Beyond the room's surface a ray runs on through the walls' solid
  // corners, so several boxes occlude it: the closest query is the test.
  c.occlusion = false;
  Rng rng(108);
  auto lattice = [&](double lo, double hi) { return std::round(rng.Uniform(lo, hi) * 256.0) / 256.0; };
  auto sign = [&]() { return rng.Uniform() < 0.5 ? -1.0 : 1.0; };
  const std::size_t n = o.quick ? 20000 : 200000;
  while (c.rays.size() < n) {
    const glm::dvec3 org(lattice(-0.99, 0.99), lattice(-0.99, 0.99), lattice(-0.99, 0.99));
    glm::dvec3 target;
    const double kind = rng.Uniform();
    const int a = int(rng.Below(3));
    if (kind < 0.4) {
      target = {sign(), sign(), sign()};
    } else if (kind < 0.8) {
      target[a] = lattice(-1.0, 1.0);
      target[(a + 1) % 3] = sign();
      target[(a + 2) % 3] = sign();
    } else {
      target[a] = sign();
      target[(a + 1) % 3] = lattice(-1.0, 1.0);
      target[(a + 2) % 3] = lattice(-1.0, 1.0);
    }
    const glm::dvec3 d = target - org;
    if (d == glm::dvec3(0.0) || !ExactF(d)) continue;
    c.rays.push_back(Rec(org, d));
  }
  return c;
}

}  // namespace

void AddLeakCases(std::vector<CaseSpec>& specs)
{
  // Full run: 400k + 300k + 300k = 10^6 rays from inside.
  specs.push_back({"leaks/icosphere", "leaks",
                   "Icosphere of level 5 (20480 triangles, vertices on a 2^-16 lattice). Rays from inside, 40% "
                   "exactly through vertices, 40% exactly through edge points, 10% through face centroids, 10% "
                   "random. Expect (closest and occlusion): a hit (a miss is a leak) naming a triangle that contains "
                   "the first crossing x* = o + t* d within check.h's delta, and (closest) |t - t*| |d| <= delta.",
                   false, [](AccelKind, const GenOptions& o) {
                     return LeakCase("leaks/icosphere", Icosphere(5), InIcosphere, o.quick ? 20000 : 400000, 101);
                   }});
  specs.push_back({"leaks/split-cube", "leaks",
                   "The cube [-1,1]^3, each face a 40x40 grid of quads split along alternating diagonals (19200 "
                   "triangles): rays exactly through its vertices, its 90-degree edges and corners, and the "
                   "diagonals. Expect as leaks/icosphere.",
                   false, [](AccelKind, const GenOptions& o) {
                     return LeakCase("leaks/split-cube", SplitCube(40), InCube, o.quick ? 20000 : 300000, 102);
                   }});
  specs.push_back({"leaks/box-room", "leaks",
                   "A room [-1,1]^3 walled by six box primitives 0.25 thick, overlapping at its edges and corners; "
                   "rays from inside (origins on a 2^-8 lattice) exactly at its corners (40%), edge points (40%) "
                   "and face points (20%). Expect (closest only: beyond the surface several walls occlude) as "
                   "leaks/icosphere: a hit on a wall at the room's surface.",
                   false, [](AccelKind, const GenOptions& o) { return BoxRoom(o); }});
  specs.push_back({"leaks/fan-cone", "leaks",
                   "A closed cone of 4096 triangles (quick: 2048): 2048 around the apex and 2048 around the base "
                   "centre (two vertices each shared by 2048 triangles; the sides are slivers of aspect ratio ~700); "
                   "a third of the vertex rays aim at those two, half of them from the axis (axis-parallel, +-0 "
                   "components). Expect as leaks/icosphere.",
                   false, [](AccelKind, const GenOptions& o) {
                     return LeakCase("leaks/fan-cone", FanCone(o.quick ? 1024 : 2048), InCone,
                                     o.quick ? 20000 : 300000, 103);
                   }});
}

}  // namespace cr::hard
