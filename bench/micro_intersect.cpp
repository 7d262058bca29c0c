// Ray-primitive and ray-box tests of kernels/intersect.h compiled as C++, in
// each precision mode: robust (watertight triangles, Woop et al. 2013; the
// stable quadratic), fast (Moller-Trumbore, textbook quadratic), fp64.
// Rays are prepared (Ray_Init) outside the timed loop unless the name says
// "WithSetup" (comparable with the SIMD probes, which prepare their rays).
// Items: ray-primitive tests. Answers are validated before timing: a ray
// through the middle must hit at the known distance, and over the seeded set
// the mode must find the hits the fp64 mode finds (up to 1%).
#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "kernels/types.h"
#include "bench/micro_common.h"

namespace cr::micro_robust {
typedef float real;
#include "kernels/intersect.h"
}  // namespace cr::micro_robust
#undef CELLRAY_KERNELS_INTERSECT_H
#undef CELLRAY_KERNELS_NUMERIC_H
#undef CELLRAY_KERNELS_SPHERE_H
#undef CELLRAY_KERNELS_TRIANGLE_H
#undef CELLRAY_KERNELS_CONE_H
#undef CELLRAY_KERNELS_RAY_H
#define CR_FAST 1
namespace cr::micro_fast {
typedef float real;
#include "kernels/intersect.h"
}  // namespace cr::micro_fast
#undef CR_FAST
#undef CELLRAY_KERNELS_INTERSECT_H
#undef CELLRAY_KERNELS_NUMERIC_H
#undef CELLRAY_KERNELS_SPHERE_H
#undef CELLRAY_KERNELS_TRIANGLE_H
#undef CELLRAY_KERNELS_CONE_H
#undef CELLRAY_KERNELS_RAY_H
#define CR_FP64 1
namespace cr::micro_fp64 {
typedef double real;
#include "kernels/intersect.h"
}  // namespace cr::micro_fp64
#undef CR_FP64

namespace cr::micro {

namespace {

// One precision mode's functions behind one name, for the templates below.
struct Robust {
  using Ray = micro_robust::Ray;
  using Real = micro_robust::real;
  static void Init(Ray* r, const RayRecord* rec) { micro_robust::Ray_Init(r, rec); }
  static int Sphere_(const Ray* r, const Sphere* s, Real* t) { return micro_robust::Sphere_Intersect(r, s, r->tmin, r->tmax, t); }
  static int Triangle_(const Ray* r, const Triangle* tr, Real* t)
  {
    Real u, v;
    return micro_robust::Triangle_Intersect(r, tr, r->tmin, r->tmax, t, &u, &v);
  }
  static int Cone_(const Ray* r, const Cone* c, Real* t) { return micro_robust::Cone_Intersect(r, c, r->tmin, r->tmax, t); }
  static int Box_(const float* lo, const float* hi, const Ray* r, Real* t)
  {
    return micro_robust::Box_Intersect(lo, hi, r, r->tmin, r->tmax, t);
  }
};

struct Fast {
  using Ray = micro_fast::Ray;
  using Real = micro_fast::real;
  static void Init(Ray* r, const RayRecord* rec) { micro_fast::Ray_Init(r, rec); }
  static int Sphere_(const Ray* r, const Sphere* s, Real* t) { return micro_fast::Sphere_Intersect(r, s, r->tmin, r->tmax, t); }
  static int Triangle_(const Ray* r, const Triangle* tr, Real* t)
  {
    Real u, v;
    return micro_fast::Triangle_Intersect(r, tr, r->tmin, r->tmax, t, &u, &v);
  }
  static int Cone_(const Ray* r, const Cone* c, Real* t) { return micro_fast::Cone_Intersect(r, c, r->tmin, r->tmax, t); }
  static int Box_(const float* lo, const float* hi, const Ray* r, Real* t)
  {
    return micro_fast::Box_Intersect(lo, hi, r, r->tmin, r->tmax, t);
  }
};

struct Fp64 {
  using Ray = micro_fp64::Ray;
  using Real = micro_fp64::real;
  static void Init(Ray* r, const RayRecord* rec) { micro_fp64::Ray_Init(r, rec); }
  static int Sphere_(const Ray* r, const Sphere* s, Real* t) { return micro_fp64::Sphere_Intersect(r, s, r->tmin, r->tmax, t); }
  static int Triangle_(const Ray* r, const Triangle* tr, Real* t)
  {
    Real u, v;
    return micro_fp64::Triangle_Intersect(r, tr, r->tmin, r->tmax, t, &u, &v);
  }
  static int Cone_(const Ray* r, const Cone* c, Real* t) { return micro_fp64::Cone_Intersect(r, c, r->tmin, r->tmax, t); }
  static int Box_(const float* lo, const float* hi, const Ray* r, Real* t)
  {
    return micro_fp64::Box_Intersect(lo, hi, r, r->tmin, r->tmax, t);
  }
};

constexpr int kRays = 1024;

const Sphere kSphere{{0.0f, 0.0f, 0.0f}, 1.0f};
const Triangle kTriangle{{-1.0f, -1.0f, 0.0f}, CR_TRI_REPORT_UV, {1.0f, -1.0f, 0.0f}, 0u, {0.0f, 1.0f, 0.0f}, 0u};
const Cone kCone{{0.0f, 0.0f, -1.0f}, 1.0f, {0.0f, 0.0f, 1.0f}, 0.5f};
const float kBoxLo[3] = {-1.0f, -1.0f, -1.0f}, kBoxHi[3] = {1.0f, 1.0f, 1.0f};

enum class Shape { Sphere, Triangle, Cone, Box };

template <class K>
int Test(Shape shape, const typename K::Ray& r, typename K::Real* t)
{
  switch (shape) {
    case Shape::Sphere: return K::Sphere_(&r, &kSphere, t);
    case Shape::Triangle: return K::Triangle_(&r, &kTriangle, t);
    case Shape::Cone: return K::Cone_(&r, &kCone, t);
    case Shape::Box: return K::Box_(kBoxLo, kBoxHi, &r, t);
  }
  return 0;
}

// The middle ray and its exact distance: from (-5, 0, 0) along +x for the
// cone (radius 0.75 at z = 0), from (0, 0, -5) along +z otherwise.
RayRecord MiddleRay(Shape shape, double& tExpected)
{
  if (shape == Shape::Cone) {
    tExpected = 4.25;
    return RayRecord{{-5.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY};
  }
  tExpected = shape == Shape::Triangle ? 5.0 : 4.0;
  return RayRecord{{0.0f, 0.0f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
}

template <class K>
int CountHits(Shape shape, const std::vector<RayRecord>& rays)
{
  int hits = 0;
  for (const auto& rec : rays) {
    typename K::Ray r;
    K::Init(&r, &rec);
    typename K::Real t;
    hits += Test<K>(shape, r, &t);
  }
  return hits;
}

template <class K>
bool Validate(Shape shape, const std::vector<RayRecord>& rays, benchmark::State& state)
{
  double tWant = 0.0;
  const RayRecord mid = MiddleRay(shape, tWant);
  typename K::Ray r;
  K::Init(&r, &mid);
  typename K::Real t = 0;
  if (!Test<K>(shape, r, &t) || (shape != Shape::Box && std::fabs(double(t) - tWant) > 1e-5 * tWant)) {
    state.SkipWithError("the middle ray does not hit at the expected distance");
    return false;
  }
  const int hits = CountHits<K>(shape, rays), want = CountHits<Fp64>(shape, rays);
  if (std::abs(hits - want) > want / 100 + 1 || want == 0 || want == int(rays.size())) {
    state.SkipWithError("hit count differs from the fp64 mode's (or the ray set is degenerate)");
    return false;
  }
  return true;
}

template <class K>
void BM_Intersect(benchmark::State& state, Shape shape)
{
  const auto recs = RaysAtOrigin(kRays, shape == Shape::Box ? 1.6f : 1.2f, 6.0f, 11);
  if (!Validate<K>(shape, recs, state)) return;
  std::vector<typename K::Ray> rays(recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) K::Init(&rays[i], &recs[i]);
  for (auto _ : state) {
    int hits = 0;
    for (const auto& r : rays) {
      typename K::Real t;
      hits += Test<K>(shape, r, &t);
      benchmark::DoNotOptimize(t);
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rays.size()));
}

template <class K>
void BM_IntersectWithSetup(benchmark::State& state, Shape shape)
{
  const auto recs = RaysAtOrigin(kRays, 1.2f, 6.0f, 11);
  if (!Validate<K>(shape, recs, state)) return;
  for (auto _ : state) {
    int hits = 0;
    for (const auto& rec : recs) {
      typename K::Ray r;
      K::Init(&r, &rec);
      typename K::Real t;
      hits += Test<K>(shape, r, &t);
      benchmark::DoNotOptimize(t);
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(recs.size()));
}

template <class K>
void Register(const char* name, Shape shape, bool withSetup = false)
{
  if (withSetup)
    benchmark::RegisterBenchmark((std::string("BM_IntersectWithSetup/") + name).c_str(), BM_IntersectWithSetup<K>, shape);
  else
    benchmark::RegisterBenchmark((std::string("BM_Intersect/") + name).c_str(), BM_Intersect<K>, shape);
}

int RegisterAll()
{
  Register<Robust>("Sphere_Robust", Shape::Sphere);
  Register<Fast>("Sphere_Fast", Shape::Sphere);
  Register<Fp64>("Sphere_Fp64", Shape::Sphere);
  Register<Robust>("Triangle_Watertight", Shape::Triangle);
  Register<Fast>("Triangle_MollerTrumbore", Shape::Triangle);
  Register<Fp64>("Triangle_WatertightFp64", Shape::Triangle);
  Register<Robust>("Cone_Robust", Shape::Cone);
  Register<Fast>("Cone_Fast", Shape::Cone);
  Register<Fp64>("Cone_Fp64", Shape::Cone);
  Register<Robust>("Box_Robust", Shape::Box);
  Register<Fast>("Box_Fast", Shape::Box);
  Register<Robust>("Sphere_Robust", Shape::Sphere, true);
  Register<Robust>("Triangle_Watertight", Shape::Triangle, true);
  Register<Fast>("Triangle_MollerTrumbore", Shape::Triangle, true);
  Register<Robust>("Cone_Robust", Shape::Cone, true);
  return 0;
}

const int kRegistered = RegisterAll();

}  // namespace

}  // namespace cr::micro
