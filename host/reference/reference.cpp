#include "host/reference/reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "host/core/error.h"
#include "host/prims/prim_host.h"

namespace cr::ref {

namespace {
constexpr std::uint32_t kLeafSize = 4;
// Ize 2013: scaling the far slab distance by 1 + 2 gamma(3) makes the double
// slab test conservative.
constexpr double kFarScale = 1.0 + 2.0 * (3.0 * 0x1p-53) / (1.0 - 3.0 * 0x1p-53);

}  // namespace

ReferenceTracer::ReferenceTracer(const Scene& scene) : scene_(scene), ranges_(scene.Ranges())
{
  const std::uint32_t n = scene.NumUnified();
  std::vector<glm::dvec3> lo(n), hi(n);
  for (std::uint32_t g = 0; g < n; ++g)
    scene.Visit(ranges_, g, [&](const auto& piece, std::uint32_t) { RefBounds(piece, lo[g], hi[g]); });
  if (scene.hasMotion) {
    // A moving piece's box swept over the shutter, rounded outward.
    motion_.resize(n);
    for (std::uint32_t g = 0; g < n; ++g) {
      motion_[g] = glm::dvec3(scene.MotionOfUnified(g));
      for (int a = 0; a < 3; ++a) {
        lo[g][a] = std::min(lo[g][a], std::nextafter(lo[g][a] + motion_[g][a], -INFINITY));
        hi[g][a] = std::max(hi[g][a], std::nextafter(hi[g][a] + motion_[g][a], INFINITY));
      }
    }
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  nodes_.reserve(n ? 2 * n / kLeafSize + 2 : 1);
  if (n == 0) {
    nodes_.push_back(Node{glm::dvec3(0.0), glm::dvec3(-1.0), 0, 0});
    return;
  }
  Build(0, n, lo, hi, 0);
}

std::uint32_t ReferenceTracer::Build(std::uint32_t begin, std::uint32_t end, std::vector<glm::dvec3>& lo,
                                     std::vector<glm::dvec3>& hi, int depth)
{
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back(Node{});
  glm::dvec3 blo(INFINITY), bhi(-INFINITY), clo(INFINITY), chi(-INFINITY);
  for (std::uint32_t i = begin; i < end; ++i) {
    std::uint32_t g = order_[i];
    blo = glm::min(blo, lo[g]);
    bhi = glm::max(bhi, hi[g]);
    glm::dvec3 c = 0.5 * (lo[g] + hi[g]);
    clo = glm::min(clo, c);
    chi = glm::max(chi, c);
  }
  nodes_[index].lo = blo;
  nodes_[index].hi = bhi;
  const std::uint32_t n = end - begin;
  glm::dvec3 ext = chi - clo;
  int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
  if (n <= kLeafSize || ext[axis] == 0.0 || depth > 100) {
    nodes_[index].first = begin;
    nodes_[index].count = n;
    return index;
  }
  std::uint32_t mid = begin + n / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::uint32_t a, std::uint32_t b) {
                     double ca = lo[a][axis] + hi[a][axis], cb = lo[b][axis] + hi[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  Build(begin, mid, lo, hi, depth + 1);
  std::uint32_t right = Build(mid, end, lo, hi, depth + 1);
  nodes_[index].first = right;
  nodes_[index].count = 0;
  return index;
}

template <typename Visit>
void ReferenceTracer::Traverse(const DRay& ray, double& tmax, Visit&& visit) const
{
  std::uint32_t stack[256];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& node = nodes_[stack[--sp]];
    double tn = ray.tmin, tf = tmax;
    double bn = -INFINITY, bf = INFINITY;
    for (int a = 0; a < 3; ++a) {
      double t0 = (node.lo[a] - ray.o[a]) * ray.inv[a];
      double t1 = (node.hi[a] - ray.o[a]) * ray.inv[a];
      if (ray.inv[a] < 0.0) std::swap(t0, t1);
      bn = cr::fmax(bn, t0);
      bf = cr::fmin(bf, t1);
    }
    tn = cr::fmax(tn, bn);
    tf = cr::fmin(tf, bf * kFarScale);
    if (!(tn <= tf)) continue;
    if (node.count > 0) {
      for (std::uint32_t i = 0; i < node.count; ++i)
        if (visit(order_[node.first + i])) return;
    } else {
      const std::uint32_t idx = static_cast<std::uint32_t>(&node - nodes_.data());
      if (sp + 2 > 256) throw RuntimeError("reference BVH deeper than its stack");
      stack[sp++] = node.first;
      stack[sp++] = idx + 1;
    }
  }
}

namespace {
DRay Shifted(const DRay& ray, const glm::dvec3& m)
{
  if (ray.time == 0.0 || m == glm::dvec3(0.0)) return ray;
  DRay r = ray;
  const glm::dvec3 s = ray.time * m;
  r.o -= s;
  r.time = 0.0;
  r.shift += std::max({std::fabs(s.x), std::fabs(s.y), std::fabs(s.z)});
  return r;
}
}  // namespace

DRay ReferenceTracer::PieceRay(std::uint32_t g, const DRay& ray) const
{
  return motion_.empty() ? ray : Shifted(ray, motion_[g]);
}

DRay ReferenceTracer::Framed(std::uint32_t prim, const DRay& ray) const
{
  return motion_.empty() || prim >= scene_.NumPrims() ? ray : Shifted(ray, glm::dvec3(scene_.prims[prim].motion));
}

int ReferenceTracer::PieceRoots(std::uint32_t g, const DRay& ray, double t[2], double* u, double* v) const
{
  const DRay r = PieceRay(g, ray);
  return scene_.Visit(ranges_, g, [&](const auto& piece, std::uint32_t) { return RefRoots(r, piece, t, u, v); });
}

int ReferenceTracer::PrimRoots(std::uint32_t prim, std::uint32_t g, const DRay& ray, double t[2]) const
{
  const std::uint32_t part = scene_.prims[prim].part;
  const DRay r = PieceRay(g, ray);
  return scene_.Visit(ranges_, g, [&](const auto& piece, std::uint32_t) { return RefPartRoots(r, piece, part, t); });
}

RefHit ReferenceTracer::Intersect(const DRay& ray) const
{
  RefHit best;
  double tmax = ray.tmax;
  Traverse(ray, tmax, [&](std::uint32_t g) {
    double t[2], u = 0.0, v = 0.0;
    int n = PieceRoots(g, ray, t, &u, &v);
    if (n > 0 && (t[0] < best.t || (t[0] == best.t && g < best.g))) {
      best.t = t[0];
      best.g = g;
      best.u = u;
      best.v = v;
      tmax = t[0];
    }
    return false;
  });
  return best;
}

RefHit ReferenceTracer::IntersectP(const DRay& ray) const
{
  RefHit any;
  double tmax = ray.tmax;
  Traverse(ray, tmax, [&](std::uint32_t g) {
    double t[2], u = 0.0, v = 0.0;
    if (PieceRoots(g, ray, t, &u, &v) > 0) {
      any.t = t[0];
      any.g = g;
      any.u = u;  // a CSG solid's leaf (IdOfHit)
      any.v = v;
      return true;
    }
    return false;
  });
  return any;
}

void ReferenceTracer::AllHits(const DRay& ray, std::vector<RefHit>& out) const
{
  out.clear();
  double tmax = ray.tmax;
  Traverse(ray, tmax, [&](std::uint32_t g) {
    double t[2], u = 0.0, v = 0.0;
    int n = PieceRoots(g, ray, t, &u, &v);
    for (int i = 0; i < n; ++i) out.push_back(RefHit{t[i], u, v, g});
    return false;
  });
}

void ReferenceTracer::PiecesOf(std::uint32_t prim, std::vector<std::uint32_t>& out) const
{
  out.clear();
  if (prim >= scene_.NumPrims()) return;
  const PrimInfo& info = scene_.prims[prim];
  const std::uint32_t base = ranges_.begin[info.type];
  for (std::uint32_t i = 0; i < info.nPieces; ++i) out.push_back(base + info.firstPiece + i);
}

double ReferenceTracer::DistanceToPrim(std::uint32_t prim, const glm::dvec3& p) const
{
  std::vector<std::uint32_t> pieces;
  PiecesOf(prim, pieces);
  double best = INFINITY;
  for (std::uint32_t g : pieces) {
    const std::uint32_t part = scene_.prims[prim].part;
    const double d =
        scene_.Visit(ranges_, g, [&](const auto& piece, std::uint32_t) { return RefPartDistance(piece, part, p); });
    best = std::min(best, d);
  }
  return best;
}

double ReferenceTracer::PrimScale(std::uint32_t prim) const
{
  std::vector<std::uint32_t> pieces;
  PiecesOf(prim, pieces);
  double s = 0.0;
  for (std::uint32_t g : pieces) s = std::max(s, scene_.Visit(ranges_, g, [](const auto& piece, std::uint32_t) { return Scale(piece); }));
  return s;
}

glm::dvec3 ReferenceTracer::GeometricNormal(std::uint32_t g, const glm::dvec3& p) const
{
  return scene_.Visit(ranges_, g, [&](const auto& piece, std::uint32_t) { return RefNormal(piece, p); });
}

glm::dvec3 ReferenceTracer::ShadingNormal(std::uint32_t g, const glm::dvec3& p, double u, double v) const
{
  glm::dvec3 ng = GeometricNormal(g, p);
  if (Prim_Is(&ranges_, CR_PRIM_TRIANGLE, g) && scene_.HasPatchNormals()) {
    const TriNormals& n = scene_.triNormals[Prim_Local(&ranges_, CR_PRIM_TRIANGLE, g)];
    glm::dvec3 ns = (1.0 - u - v) * glm::dvec3(n[0]) + u * glm::dvec3(n[1]) + v * glm::dvec3(n[2]);
    double len = glm::length(ns);
    if (len > 0.0) return ns / len;
  }
  return ng;
}

HitRecord ReferenceTracer::ToRecord(const RefHit& h, bool occlusion) const
{
  HitRecord r{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
  if (!h.Found()) return r;
  r.prim = IdOfHit(h);
  if (occlusion) {
    r.t = 0.0f;
    return r;
  }
  r.t = static_cast<float>(h.t);
  if (Prim_Is(&ranges_, CR_PRIM_TRIANGLE, h.g) &&
      (scene_.triangles[Prim_Local(&ranges_, CR_PRIM_TRIANGLE, h.g)].flags & CR_TRI_REPORT_UV)) {
    r.u = static_cast<float>(h.u);
    r.v = static_cast<float>(h.v);
  }
  return r;
}

}  // namespace cr::ref

namespace cr::ref {

HitRecord ReferenceTracer::ToUnifiedRecord(const RefHit& h, bool occlusion) const
{
  HitRecord r{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
  if (!h.Found()) return r;
  r.prim = h.g;
  r.t = occlusion ? 0.0f : static_cast<float>(h.t);
  if (Prim_Is(&ranges_, CR_PRIM_CSG, h.g) || (!occlusion && Prim_Is(&ranges_, CR_PRIM_TRIANGLE, h.g))) {
    r.u = static_cast<float>(h.u);
    r.v = static_cast<float>(h.v);
  }
  return r;
}

}  // namespace cr::ref
