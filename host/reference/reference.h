// The fp64 reference tracer (`--backend reference`): the ground truth of every
// error figure. A plain median-split BVH over double-precision bounds that are
// rounded outward, a conservative slab test, and exact-as-double primitive
// tests (geometry_d.h). Independent of the code under test on purpose: it
// shares the scene, not the kernels.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "kernels/types.h"
#include "host/reference/geometry_d.h"
#include "host/scene/scene.h"

namespace cr::ref {

struct RefHit {
  double t = INFINITY;
  double u = 0.0, v = 0.0;
  std::uint32_t g = CR_NO_HIT;  // unified index of the piece
  bool Found() const { return g != CR_NO_HIT; }
};

class ReferenceTracer {
 public:
  explicit ReferenceTracer(const Scene& scene);

  // Closest hit in [tmin, tmax] (ties: lower unified index).
  RefHit Intersect(const DRay& ray) const;
  // Some hit in [tmin, tmax], if any.
  RefHit IntersectP(const DRay& ray) const;
  // Every root of every piece in [tmin, tmax] (unsorted).
  void AllHits(const DRay& ray, std::vector<RefHit>& out) const;
  // The ray as piece g / primitive id `prim` sees it at the ray's time: its
  // origin shifted by -time * motion into the rest frame of the piece's
  // geometry, time 0 (the ray itself for a static piece or time 0).
  DRay PieceRay(std::uint32_t g, const DRay& ray) const;
  DRay Framed(std::uint32_t prim, const DRay& ray) const;
  // Roots of one piece in [tmin, tmax] at the ray's time; returns their count (<= 2).
  int PieceRoots(std::uint32_t g, const DRay& ray, double t[2], double* u = nullptr, double* v = nullptr) const;
  // Roots of primitive id `prim` on its piece g: PieceRoots, or for a part
  // of a piece (a CSG leaf) the roots where that part bounds the piece.
  int PrimRoots(std::uint32_t prim, std::uint32_t g, const DRay& ray, double t[2]) const;
  // The primitive id a hit names (a CSG solid's leaf, by its u).
  std::uint32_t IdOfHit(const RefHit& h) const { return scene_.IdOfHit(h.g, h.u); }
  // Distance from p to the surface of primitive id `prim` (all its pieces,
  // at rest: a point of a moving primitive's frame, Framed); INFINITY for an
  // id without geometry.
  double DistanceToPrim(std::uint32_t prim, const glm::dvec3& p) const;
  // Largest coordinate magnitude of the points defining primitive `prim`
  // (vertices; centre, base and apex plus radii): the scale of the rounding
  // a float tracer makes when it intersects it.
  double PrimScale(std::uint32_t prim) const;
  // Unified indices of the pieces of primitive id `prim`.
  void PiecesOf(std::uint32_t prim, std::vector<std::uint32_t>& out) const;
  // Geometric outward normal of piece g at p (unit length).
  glm::dvec3 GeometricNormal(std::uint32_t g, const glm::dvec3& p) const;
  // Shading normal of piece g at p: patch vertex normals interpolated with
  // (u, v), else the geometric normal (unit length).
  glm::dvec3 ShadingNormal(std::uint32_t g, const glm::dvec3& p, double u, double v) const;

  // The record a tracer reports for this hit (prim id; u, v only for whole
  // triangle statements); occlusion records have t = 0.
  HitRecord ToRecord(const RefHit& h, bool occlusion) const;
  // The renderer's internal form (TraceConfig::unifiedHits): prim = g.
  HitRecord ToUnifiedRecord(const RefHit& h, bool occlusion) const;

  const Scene& GetScene() const { return scene_; }
  std::size_t NodeCount() const { return nodes_.size(); }

 private:
  struct Node {
    glm::dvec3 lo, hi;
    std::uint32_t first = 0;  // leaf: first index into order_; interior: right child
    std::uint32_t count = 0;  // 0: interior (left child is the next node)
  };
  std::uint32_t Build(std::uint32_t begin, std::uint32_t end, std::vector<glm::dvec3>& lo,
                      std::vector<glm::dvec3>& hi, int depth);
  template <typename Visit>
  void Traverse(const DRay& ray, double& tmax, Visit&& visit) const;

  const Scene& scene_;
  PrimRanges ranges_{};
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<glm::dvec3> motion_;  // per unified piece; empty for a static scene
};

}  // namespace cr::ref
