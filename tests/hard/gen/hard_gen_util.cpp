#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"
#include "host/core/error.h"
#include "host/reference/reference.h"
#include "host/scene/nff.h"

namespace cr::hard {

namespace kern {
// The planes exactly as the builders and traversals compute them.
#include "kernels/grid.h"
#include "kernels/octree.h"
}  // namespace kern

glm::dvec3 Rng::UnitVector()
{
  for (;;) {
    glm::dvec3 v(Uniform(-1, 1), Uniform(-1, 1), Uniform(-1, 1));
    const double l2 = glm::dot(v, v);
    if (l2 > 1e-4 && l2 <= 1.0) return v / std::sqrt(l2);
  }
}

SceneBuilder::SceneBuilder() : scene_(std::make_shared<Scene>())
{
  scene_->path = "generated";
  scene_->hasCamera = true;
  scene_->materials.push_back(Material{});
}

std::uint32_t SceneBuilder::Sphere(const glm::dvec3& c, double r)
{
  const std::uint32_t id = NextId();
  NffValues st("s", scene_->path, id + 1, {c.x, c.y, c.z, r});
  ReadGeometry(st, *scene_);
  return id;
}

std::uint32_t SceneBuilder::Triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c)
{
  return Polygon({a, b, c});
}

std::uint32_t SceneBuilder::Polygon(const std::vector<glm::dvec3>& v)
{
  const std::uint32_t id = NextId();
  AddPolygon(*scene_, PrimKind::kPolygon, v, nullptr, 0, id + 1, "generated");
  return id;
}

std::uint32_t SceneBuilder::Cone(const glm::dvec3& base, double baseRadius, const glm::dvec3& apex, double apexRadius)
{
  const std::uint32_t id = NextId();
  NffValues st("c", scene_->path, id + 1, {base.x, base.y, base.z, baseRadius, apex.x, apex.y, apex.z, apexRadius});
  ReadGeometry(st, *scene_);
  return id;
}

std::uint32_t SceneBuilder::AxisBox(const glm::dvec3& lo, const glm::dvec3& hi)
{
  const std::uint32_t id = NextId();
  NffValues st("box", scene_->path, id + 1, {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
  ReadGeometry(st, *scene_);
  return id;
}

std::uint32_t SceneBuilder::Quadric(const std::array<double, 10>& k, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const std::uint32_t id = NextId();
  std::vector<double> v(k.begin(), k.end());
  v.insert(v.end(), {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
  NffValues st("quadric", scene_->path, id + 1, std::move(v));
  ReadGeometry(st, *scene_);
  return id;
}

std::uint32_t SceneBuilder::Polyhedron(const std::vector<glm::dvec4>& planes)
{
  const std::uint32_t id = NextId();
  std::vector<double> v = {double(planes.size())};
  for (const glm::dvec4& p : planes) v.insert(v.end(), {p.x, p.y, p.z, p.w});
  NffValues st("polyhedron", scene_->path, id + 1, std::move(v));
  ReadGeometry(st, *scene_);
  return id;
}

std::uint32_t SceneBuilder::Box(const glm::dvec3& lo, const glm::dvec3& hi)
{
  const std::uint32_t first = NextId();
  auto p = [&](int x, int y, int z) { return glm::dvec3(x ? hi.x : lo.x, y ? hi.y : lo.y, z ? hi.z : lo.z); };
  Polygon({p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1)});
  Polygon({p(1, 0, 0), p(1, 0, 1), p(1, 1, 1), p(1, 1, 0)});
  Polygon({p(0, 0, 0), p(0, 0, 1), p(1, 0, 1), p(1, 0, 0)});
  Polygon({p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1)});
  Polygon({p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0)});
  Polygon({p(0, 0, 1), p(0, 1, 1), p(1, 1, 1), p(1, 0, 1)});
  return first;
}

void Thin(std::vector<RayRecord>& rays, std::size_t keep)
{
  if (keep == 0 || rays.size() <= keep) return;
  const double stride = double(rays.size()) / double(keep);
  std::vector<RayRecord> out;
  out.reserve(keep);
  for (std::size_t k = 0; k < keep; ++k) out.push_back(rays[std::size_t(double(k) * stride)]);
  rays.swap(out);
}

float GridPlane(const GridHeader& h, int axis, int i) { return kern::Grid_Plane(&h, axis, i); }

float OctreePlane(const OctreeHeader& h, int axis, unsigned level, unsigned i)
{
  return kern::Octree_Plane(&h, axis, level, i);
}

int OctreeMaxDepth() { return CR_OCTREE_MAX_DEPTH; }

namespace {

void SortUnique(std::vector<float>& v)
{
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// Every node's boundary and mid planes (depth first, coordinates tracked).
void OctreeNodePlanes(const OctreeData& o, std::uint32_t ni, unsigned level, const unsigned c[3], Planes& out)
{
  const OctreeNode& n = o.nodes[ni];
  for (int a = 0; a < 3; ++a) {
    out.axis[a].push_back(OctreePlane(o.header, a, level, c[a]));
    out.axis[a].push_back(OctreePlane(o.header, a, level, c[a] + 1));
  }
  if (n.childMask == 0) return;
  for (int a = 0; a < 3; ++a) out.axis[a].push_back(OctreePlane(o.header, a, level + 1, 2 * c[a] + 1));
  std::uint32_t k = 0;
  for (unsigned oct = 0; oct < 8; ++oct) {
    if (!((n.childMask >> oct) & 1u)) continue;
    const unsigned cc[3] = {2 * c[0] + (oct & 1u), 2 * c[1] + ((oct >> 1) & 1u), 2 * c[2] + ((oct >> 2) & 1u)};
    OctreeNodePlanes(o, n.first + k++, level + 1, cc, out);
  }
}

}  // namespace

Planes PlanesOf(const AccelData& data)
{
  Planes p;
  switch (data.kind) {
    case AccelKind::Grid: {
      const GridHeader& h = data.grid.header;
      for (int a = 0; a < 3; ++a) {
        for (int i = 0; i <= int(h.res[a]); ++i) p.axis[a].push_back(GridPlane(h, a, i));
        p.lo[a] = h.bmin[a];
        p.hi[a] = h.bmax[a];
      }
      break;
    }
    case AccelKind::HGrid: {
      // Every level: the root's planes and every child grid's.
      const GridHeader& h = data.hgrid.header;
      for (int a = 0; a < 3; ++a) {
        for (int i = 0; i <= int(h.res[a]); ++i) p.axis[a].push_back(GridPlane(h, a, i));
        p.lo[a] = h.bmin[a];
        p.hi[a] = h.bmax[a];
      }
      for (const GridHeader& sub : data.hgrid.subs)
        if (sub.nRefs != 0)
          for (int a = 0; a < 3; ++a)
            for (int i = 0; i <= int(sub.res[a]); ++i) p.axis[a].push_back(GridPlane(sub, a, i));
      break;
    }
    case AccelKind::Octree: {
      const OctreeData& o = data.octree;
      const unsigned c[3] = {0, 0, 0};
      if (!o.nodes.empty()) OctreeNodePlanes(o, 0, 0, c, p);
      for (int a = 0; a < 3; ++a) {
        p.lo[a] = OctreePlane(o.header, a, 0, 0);
        p.hi[a] = OctreePlane(o.header, a, 0, 1);
      }
      break;
    }
    case AccelKind::BVH: {
      for (const BVHNode& n : data.bvh.nodes)
        for (int a = 0; a < 3; ++a) {
          p.axis[a].push_back(n.bmin[a]);
          p.axis[a].push_back(n.bmax[a]);
        }
      if (!data.bvh.nodes.empty())
        for (int a = 0; a < 3; ++a) {
          p.lo[a] = data.bvh.nodes[0].bmin[a];
          p.hi[a] = data.bvh.nodes[0].bmax[a];
        }
      break;
    }
  }
  for (auto& v : p.axis) SortUnique(v);
  return p;
}

double OwnRoot(const ref::ReferenceTracer& tr, std::uint32_t prim, const RayRecord& ray, double minT)
{
  std::vector<std::uint32_t> pieces;
  tr.PiecesOf(prim, pieces);
  ref::DRay r = ref::MakeRay(ray);
  r.tmin = minT;
  r.tmax = INFINITY;
  double best = INFINITY;
  for (std::uint32_t g : pieces) {
    double t[2];
    const int n = tr.PieceRoots(g, r, t);
    for (int k = 0; k < n; ++k) best = std::min(best, t[k]);
  }
  return best;
}

}  // namespace cr::hard
