// Shared pieces of the hard-case generators (hard_gen_*.cpp): a seeded
// random source that is the same on every platform, a scene builder with
// the loader's id rules, exact-arithmetic helpers, and the cell planes of a
// built structure. Internal to bench/; the cases themselves are in
// hard_cases.h.
#pragma once

#include <array>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "host/accel/accel.h"
#include "tests/hard/gen/hard_cases.h"
#include "host/scene/scene.h"

namespace cr::hard {

// Each family registers its cases (hard_gen_<family>.cpp).
void AddLeakCases(std::vector<CaseSpec>& specs);
void AddCellCases(std::vector<CaseSpec>& specs);
void AddAxisCases(std::vector<CaseSpec>& specs);
void AddTinyFarCases(std::vector<CaseSpec>& specs);
void AddGrazingCases(std::vector<CaseSpec>& specs);
void AddSelfCases(std::vector<CaseSpec>& specs);
void AddDegenerateCases(std::vector<CaseSpec>& specs);
void AddExtremeCases(std::vector<CaseSpec>& specs);
void AddHugeCases(std::vector<CaseSpec>& specs);
void AddSdfCases(std::vector<CaseSpec>& specs);
void AddCsgCases(std::vector<CaseSpec>& specs);

// SplitMix64 (Steele, Lea & Flood 2014): the same numbers from a seed on any
// standard library, unlike std::uniform_real_distribution.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t Next()
  {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return double(Next() >> 11) * 0x1p-53; }  // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  std::uint32_t Below(std::uint32_t n) { return std::uint32_t(Uniform() * n); }
  glm::dvec3 InBox(const glm::dvec3& lo, const glm::dvec3& hi)
  {
    return {Uniform(lo.x, hi.x), Uniform(lo.y, hi.y), Uniform(lo.z, hi.z)};
  }
  glm::dvec3 UnitVector();

 private:
  std::uint64_t s_;
};

// Builds a scene statement by statement, ids in order as the loaders number
// them (FORMATS.md).
class SceneBuilder {
 public:
  SceneBuilder();
  std::uint32_t Sphere(const glm::dvec3& c, double r);
  std::uint32_t Triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);
  // A polygon statement (split into triangle pieces by the loader's rules).
  std::uint32_t Polygon(const std::vector<glm::dvec3>& v);
  std::uint32_t Cone(const glm::dvec3& base, double baseRadius, const glm::dvec3& apex, double apexRadius);
  // Six quads (polygon statements) bounding [lo, hi]: a backstop every ray
  // from inside ends on. Returns the first id.
  std::uint32_t Box(const glm::dvec3& lo, const glm::dvec3& hi);
  // An axis-aligned box primitive (NFF extension `box`).
  std::uint32_t AxisBox(const glm::dvec3& lo, const glm::dvec3& hi);
  // `quadric` statement: coefficients A..J (POV-Ray's order), clip box.
  std::uint32_t Quadric(const std::array<double, 10>& k, const glm::dvec3& lo, const glm::dvec3& hi);
  // `polyhedron` statement: planes (a, b, c, d), a x + b y + c z + d <= 0.
  std::uint32_t Polyhedron(const std::vector<glm::dvec4>& planes);
  std::uint32_t NextId() const { return scene_->NumPrims(); }
  Scene& Get() { return *scene_; }
  std::shared_ptr<const Scene> Finish() { return std::move(scene_); }

 private:
  std::shared_ptr<Scene> scene_;
};

inline RayRecord Rec(const glm::dvec3& o, const glm::dvec3& d, float tmin = 0.0f, float tmax = INFINITY)
{
  return RayRecord{{float(o.x), float(o.y), float(o.z)}, tmin, {float(d.x), float(d.y), float(d.z)}, tmax};
}
inline RayRecord RecF(const glm::vec3& o, const glm::vec3& d, float tmin = 0.0f, float tmax = INFINITY)
{
  return RayRecord{{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

// Exactly representable as float?
inline constexpr double kPi = 3.14159265358979323846;

inline bool ExactF(double x) { return double(float(x)) == x; }
inline bool ExactF(const glm::dvec3& v) { return ExactF(v.x) && ExactF(v.y) && ExactF(v.z); }
inline glm::dvec3 D(const glm::vec3& v) { return {v.x, v.y, v.z}; }
inline glm::dvec3 D(const float* v) { return {v[0], v[1], v[2]}; }
// Rounds to a multiple of `step` (a power of two): such coordinates add and
// subtract exactly in float as long as their magnitudes stay small.
inline double Snap(double x, double step) { return std::round(x / step) * step; }
inline glm::dvec3 Snap(const glm::dvec3& v, double step) { return {Snap(v.x, step), Snap(v.y, step), Snap(v.z, step)}; }

// Keeps every `stride`-th element so that about `keep` remain (a deterministic
// thinning of a ray list for quick runs).
void Thin(std::vector<RayRecord>& rays, std::size_t keep);

// Cell planes of a built structure, per axis, ascending, and its outer box:
// grid planes (Grid_Plane), octree planes of every level down to the
// deepest one built (Octree_Plane), BVH node faces.
struct Planes {
  std::vector<float> axis[3];
  glm::vec3 lo{0.0f}, hi{0.0f};
};
Planes PlanesOf(const AccelData& data);
// Planes of a grid or octree header alone (the same values as PlanesOf).
float GridPlane(const GridHeader& h, int axis, int i);
float OctreePlane(const OctreeHeader& h, int axis, unsigned level, unsigned i);
// CR_OCTREE_MAX_DEPTH of kernels/octree.h.
int OctreeMaxDepth();

// For NotSelf: the reference's first root on primitive `prim` along `ray`
// beyond `minT` (INFINITY if none), so that a legitimate re-hit (the far
// side of a sphere entered) is told apart from self-intersection.
double OwnRoot(const ref::ReferenceTracer& tr, std::uint32_t prim, const RayRecord& ray, double minT);

}  // namespace cr::hard
