// Cell boundaries: rays along the cell planes, cell edges and through the
// cell corners of the structure under test, rays starting exactly on a
// boundary or on the structure's outer box, and primitives lying exactly on
// cell planes. The planes are read from the built structure (Grid_Plane,
// Octree_Plane, BVH node faces), so they are exact for it: the case is
// generated once per structure.
//
// For the grid and the octree the primitives are placed in two passes: the
// scene is built with the same statements at provisional positions, the
// planes are read, the primitives are moved onto them and the structure is
// rebuilt; the planes do not move (they depend on the world box, fixed by
// eight corner spheres, and on the primitive count), which the generator
// checks. A BVH's planes are its primitives' own bounds, so quads and
// triangles in axis planes lie on node faces by construction.
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"
#include "host/core/error.h"

namespace cr::hard {

namespace {

// Planes inside the content region [1, 7] (the frame spans [0, 8]).
std::vector<float> Inner(const std::vector<float>& v)
{
  std::vector<float> out;
  for (float p : v)
    if (p >= 1.0f && p <= 7.0f) out.push_back(p);
  if (out.size() < 4) throw RuntimeError("hard case cells: fewer than 4 cell planes inside the content region");
  return out;
}

struct Picker {
  Rng& rng;
  const std::vector<float>* axis[3];
  // Plane i positions apart from a random one, on axis a (clamped to the list).
  std::size_t Index(int a) { return rng.Below(std::uint32_t(axis[a]->size() - 1)); }
  float At(int a, std::size_t i) const { return (*axis[a])[std::min(i, axis[a]->size() - 1)]; }
};

// The scene: frame spheres (ids 0..7), random content, then primitives on
// the planes `inner` (per axis; nominal planes on the first pass).
std::shared_ptr<const Scene> CellScene(const std::vector<float> inner[3])
{
  Rng rng(202);
  SceneBuilder b;
  for (int k = 0; k < 8; ++k) b.Sphere({8.0 * (k & 1), 8.0 * ((k >> 1) & 1), 8.0 * ((k >> 2) & 1)}, 0.1);
  for (int i = 0; i < 10; ++i) b.Sphere(rng.InBox(glm::dvec3(1.5), glm::dvec3(6.5)), rng.Uniform(0.1, 0.5));
  for (int i = 0; i < 10; ++i) {
    const glm::dvec3 c = rng.InBox(glm::dvec3(1.5), glm::dvec3(6.5));
    b.Triangle(c + 0.6 * rng.UnitVector(), c + 0.6 * rng.UnitVector(), c + 0.6 * rng.UnitVector());
  }
  for (int i = 0; i < 4; ++i) {
    const glm::dvec3 c = rng.InBox(glm::dvec3(2), glm::dvec3(6));
    b.Cone(c, rng.Uniform(0.1, 0.4), c + rng.UnitVector(), rng.Uniform(0.0, 0.3));
  }
  Picker pk{rng, {&inner[0], &inner[1], &inner[2]}};
  // Axis-aligned quads on a plane, corners on cell corners.
  for (int i = 0; i < 6; ++i) {
    const int a = i % 3, u = (a + 1) % 3, w = (a + 2) % 3;
    const float pa = pk.At(a, pk.Index(a));
    const std::size_t u0 = pk.Index(u), w0 = pk.Index(w);
    const float u1 = pk.At(u, u0 + 1 + rng.Below(2)), w1 = pk.At(w, w0 + 1 + rng.Below(2));
    glm::dvec3 p[4];
    for (int k = 0; k < 4; ++k) {
      p[k][a] = pa;
      p[k][u] = (k == 1 || k == 2) ? u1 : pk.At(u, u0);
      p[k][w] = (k >= 2) ? w1 : pk.At(w, w0);
    }
    b.Polygon({p[0], p[1], p[2], p[3]});
  }
  // Spheres centred on cell corners, touching the neighbouring planes.
  for (int i = 0; i < 6; ++i) {
    glm::dvec3 c;
    double r = INFINITY;
    for (int a = 0; a < 3; ++a) {
      const std::size_t k = 1 + pk.Index(a) % (inner[a].size() - 2);
      c[a] = pk.At(a, k);
      r = std::min({r, c[a] - pk.At(a, k - 1), pk.At(a, k + 1) - c[a]});
    }
    b.Sphere(c, r);
  }
  // Cylinders around cell edges.
  for (int i = 0; i < 3; ++i) {
    const int a = i, u = (a + 1) % 3, w = (a + 2) % 3;
    glm::dvec3 base, apex;
    base[u] = apex[u] = pk.At(u, pk.Index(u));
    base[w] = apex[w] = pk.At(w, pk.Index(w));
    const std::size_t k = pk.Index(a);
    base[a] = pk.At(a, k);
    apex[a] = pk.At(a, k + 2);
    b.Cone(base, 0.3 * (pk.At(u, 1) - pk.At(u, 0)), apex, 0.3 * (pk.At(u, 1) - pk.At(u, 0)));
  }
  // Triangles in cell planes with their vertices on cell corners.
  for (int i = 0; i < 6; ++i) {
    const int a = i % 3, u = (a + 1) % 3, w = (a + 2) % 3;
    const float pa = pk.At(a, pk.Index(a));
    const std::size_t u0 = pk.Index(u), w0 = pk.Index(w);
    glm::dvec3 p0, p1, p2;
    p0[a] = p1[a] = p2[a] = pa;
    p0[u] = pk.At(u, u0), p0[w] = pk.At(w, w0);
    p1[u] = pk.At(u, u0 + 2), p1[w] = pk.At(w, w0);
    p2[u] = pk.At(u, u0), p2[w] = pk.At(w, w0 + 1);
    b.Triangle(p0, p1, p2);
  }
  return b.Finish();
}

float Pick(Rng& rng, const std::vector<float>& v) { return v[rng.Below(std::uint32_t(v.size()))]; }
float Zero(Rng& rng) { return rng.Uniform() < 0.5 ? 0.0f : -0.0f; }
float Sign(Rng& rng) { return rng.Uniform() < 0.5 ? 1.0f : -1.0f; }

std::vector<RayRecord> CellRays(const Planes& pl, std::size_t count)
{
  Rng rng(203);
  std::vector<float> in[3];
  for (int a = 0; a < 3; ++a) in[a] = Inner(pl.axis[a]);
  const glm::dvec3 lo = D(pl.lo), hi = D(pl.hi);
  auto inside = [&] { return glm::vec3(rng.InBox(lo, hi)); };
  auto corner = [&] { return glm::vec3(Pick(rng, in[0]), Pick(rng, in[1]), Pick(rng, in[2])); };
  std::vector<RayRecord> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const int family = int(rays.size() % 6);
    glm::vec3 o(0.0f), d(0.0f);
    float tmin = 0.0f;
    switch (family) {
      case 0: {  // along a cell edge line: two coordinates on planes, the third travels, +-0 elsewhere
        const int k = int(rng.Below(3)), u = (k + 1) % 3, w = (k + 2) % 3;
        o[u] = Pick(rng, in[u]);
        o[w] = Pick(rng, in[w]);
        const double r = rng.Uniform();
        o[k] = r < 0.25 ? float(lo[k] - 1.0) : r < 0.5 ? float(hi[k] + 1.0) : r < 0.75 ? Pick(rng, in[k]) : inside()[k];
        d[k] = Sign(rng);
        d[u] = Zero(rng);
        d[w] = Zero(rng);
        break;
      }
      case 1: {  // in a cell plane
        const int a = int(rng.Below(3));
        o = inside();
        o[a] = Pick(rng, in[a]);
        d = glm::vec3(rng.UnitVector());
        d[a] = Zero(rng);
        break;
      }
      case 2: {  // from a cell corner: to another corner, diagonally, or anywhere
        o = corner();
        const double r = rng.Uniform();
        if (r < 0.5) {
          d = corner() - o;
          if (d == glm::vec3(0.0f)) d = glm::vec3(1.0f, -0.0f, 0.0f);
        } else if (r < 0.75) {
          d = glm::vec3(Sign(rng), Sign(rng), Sign(rng));
        } else {
          d = glm::vec3(rng.UnitVector());
        }
        break;
      }
      case 3: {  // through a corner from afar: o = C - s e exactly where float allows
        const glm::vec3 c = corner();
        glm::vec3 e(Sign(rng), Sign(rng), rng.Uniform() < 0.3 ? Zero(rng) : Sign(rng));
        const float s = float(std::ldexp(1.0, 1 + int(rng.Below(3))));
        o = c - s * e;
        d = e;
        break;
      }
      case 4: {  // on the outer box: inward, outward or along a face
        const int a = int(rng.Below(3));
        o = inside();
        o[a] = rng.Uniform() < 0.5 ? pl.lo[a] : pl.hi[a];
        if (rng.Uniform() < 0.3) {
          const int b2 = (a + 1 + int(rng.Below(2))) % 3;
          o[b2] = rng.Uniform() < 0.5 ? pl.lo[b2] : pl.hi[b2];
        }
        d = glm::vec3(rng.UnitVector());
        const double r = rng.Uniform();
        if (r < 0.3) d[a] = Zero(rng);
        break;
      }
      default: {  // starting exactly on a plane, tmin on another plane's crossing
        const int a = int(rng.Below(3));
        o = inside();
        o[a] = Pick(rng, in[a]);
        d = glm::vec3(rng.UnitVector());
        const float p = Pick(rng, in[a]);
        const float t = (p - o[a]) / d[a];
        tmin = t > 0.0f && std::isfinite(t) ? t : 0.0f;
        break;
      }
    }
    if (d == glm::vec3(0.0f)) continue;
    rays.push_back(RecF(o, d, tmin));
  }
  return rays;
}

bool SameGrid(const GridHeader& a, const GridHeader& b)
{
  return std::memcmp(a.bmin, b.bmin, 12) == 0 && std::memcmp(a.bmax, b.bmax, 12) == 0 &&
         std::memcmp(a.cellSize, b.cellSize, 12) == 0 && std::memcmp(a.res, b.res, 12) == 0;
}

// The planes primitives are placed on: all of the structure's for the grid
// and the octree, whose planes depend only on the world box and the
// primitive count; the root's for the hierarchical grid, whose child grids
// follow the cells' reference counts, which the placement changes (rays
// still follow the planes of every level, CellRays below).
Planes PlacementPlanes(const AccelData& data)
{
  if (data.kind != AccelKind::HGrid) return PlanesOf(data);
  AccelData root;
  root.kind = AccelKind::Grid;
  root.grid.header = data.hgrid.header;
  return PlanesOf(root);
}

bool SameHeader(const AccelData& a, const AccelData& b)
{
  if (a.kind == AccelKind::Grid) return SameGrid(a.grid.header, b.grid.header);
  if (a.kind == AccelKind::HGrid) return SameGrid(a.hgrid.header, b.hgrid.header);
  if (a.kind == AccelKind::Octree)
    return std::memcmp(a.octree.header.rootMin, b.octree.header.rootMin, 12) == 0 &&
           a.octree.header.rootSize == b.octree.header.rootSize;
  return true;
}

HardCase CellCase(AccelKind accel, const GenOptions& o)
{
  // Nominal planes for the first pass: multiples of 0.5.
  std::vector<float> nominal[3];
  for (int a = 0; a < 3; ++a)
    for (int i = 2; i <= 14; ++i) nominal[a].push_back(0.5f * float(i));
  std::shared_ptr<const Scene> scene = CellScene(nominal);
  AccelParams params;
  params.gridDensity = 4.0;
  params.octreeLeaf = 2;
  params.hgridTopDensity = 4.0;  // root planes as the grid's
  params.hgridLeaf = 1;          // child grids in every cell of two references or more
  params.hgridDensity = 8.0;
  AccelData data = BuildAccel(*scene, accel, params);
  if (accel != AccelKind::BVH) {
    const Planes first = PlacementPlanes(data);
    std::vector<float> inner[3];
    for (int a = 0; a < 3; ++a) inner[a] = Inner(first.axis[a]);
    scene = CellScene(inner);
    AccelData again = BuildAccel(*scene, accel, params);
    if (!SameHeader(data, again))
      throw RuntimeError("hard case cells: the planes moved when primitives were placed on them");
    data = std::move(again);
  }
  HardCase c;
  c.name = "cells/planes-edges-corners";
  c.scene = scene;
  c.params = params;
  c.rays = CellRays(PlanesOf(data), o.quick ? 6000 : 60000);
  c.expect = Expect::Reference;
  return c;
}

}  // namespace

void AddCellCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"cells/planes-edges-corners", "cells",
                   "Per structure, from its own planes (grid: Grid_Plane; octree: Octree_Plane of every node; bvh: "
                   "node faces; hgrid: the planes of the root and of every child grid; primitives on the root's): rays along cell edge lines (+-0 components), in cell planes, from and through "
                   "cell corners, starting on the outer box (inward, outward, along a face), starting on a plane "
                   "with tmin on another; quads, triangles, corner-centred spheres touching the planes and "
                   "cylinders around cell edges placed exactly on the planes. Expect: the reference's answer "
                   "(agree or tie), closest and occlusion.",
                   true, CellCase});
}

}  // namespace cr::hard
