// cellray._cellray: the Python API's native part (nanobind). The package
// python/cellray/__init__.py checks arguments and documents the API
// (docs/PYTHON.md); this file binds the C++ core:
//  - Scene: LoadScene, or triangles and spheres from arrays; counts, bounds,
//    camera, lights; rays (GenerateRays, as `cellray rays`); render.
//  - Tracer: any backend x structure x precision; Trace on the caller's
//    (N, 8) float32 array in place (RaySpan), the GIL released; hits in the
//    .hits record form (FORMATS.md) exposed as numpy views of the buffer
//    they were written to; normals on demand (SurfaceAt).
//  - check: the fp64 reference's verdicts (host/reference/check.h).
// Errors: InputError -> ValueError, RuntimeError (OpenCL names included) ->
// RuntimeError.
#include <cmath>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "host/core/error.h"
#include "host/io/rays_io.h"
#include "host/rays/raygen.h"
#include "host/reference/check.h"
#include "host/reference/geometry_d.h"
#include "host/reference/reference.h"
#include "host/render/image_io.h"
#include "host/render/renderer.h"
#include "host/scene/area_light.h"
#include "host/scene/camera.h"
#include "host/scene/surface.h"
#include "host/trace/tracer.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace cr;

namespace {

using RayArray = nb::ndarray<const float, nb::shape<-1, 8>, nb::c_contig, nb::device::cpu>;
using TimeArray = nb::ndarray<const float, nb::shape<-1>, nb::c_contig, nb::device::cpu>;

// Whether rays[b, e) all pass the quick test (finite origin, direction and
// tmin, tmax not NaN, 0 <= tmin <= tmax, direction not zero). With AVX2 (the
// machine's; chosen at run time), one 32-byte record is one vector.
bool RaysLookValidScalar(const RayRecord* rays, std::size_t b, std::size_t e)
{
  bool ok = true;
  for (std::size_t i = b; i < e; ++i) {
    const RayRecord& x = rays[i];
    ok &= std::isfinite(x.org[0]) & std::isfinite(x.org[1]) & std::isfinite(x.org[2]) & std::isfinite(x.dir[0]) &
          std::isfinite(x.dir[1]) & std::isfinite(x.dir[2]) & std::isfinite(x.tmin) & (x.tmin >= 0.0f) &
          (x.tmin <= x.tmax) & ((x.dir[0] != 0.0f) | (x.dir[1] != 0.0f) | (x.dir[2] != 0.0f));
  }
  return ok;
}

#if defined(__x86_64__)
__attribute__((target("avx2"))) bool RaysLookValidAvx2(const RayRecord* rays, std::size_t b, std::size_t e)
{
  // Lanes: ox oy oz tmin dx dy dz tmax.
  const __m256 absMask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 maxFinite = _mm256_set1_ps(3.40282347e38f);
  __m256 bad = _mm256_setzero_ps();
  for (std::size_t i = b; i < e; ++i) {
    const __m256 x = _mm256_loadu_ps(reinterpret_cast<const float*>(rays + i));
    const __m256 ax = _mm256_and_ps(x, absMask);
    // Not finite (NaN compares true with NLE_UQ): lanes 0-6; lane 7 (tmax) may be +inf but not NaN.
    const __m256 nonFinite = _mm256_cmp_ps(ax, maxFinite, _CMP_NLE_UQ);
    const __m256 isNan = _mm256_cmp_ps(x, x, _CMP_UNORD_Q);
    bad = _mm256_or_ps(bad, _mm256_blend_ps(nonFinite, isNan, 0x80));
    // tmin < 0 or tmin > tmax (lane 3 against lane 7).
    const __m128 hi = _mm256_extractf128_ps(x, 1);
    const __m128 lo = _mm256_castps256_ps128(x);
    const __m128 tmin = _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(3, 3, 3, 3));
    const __m128 tmax = _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(3, 3, 3, 3));
    __m128 b4 = _mm_or_ps(_mm_cmplt_ss(tmin, _mm_setzero_ps()), _mm_cmpgt_ss(tmin, tmax));
    // Zero direction: lanes 4-6 all zero.
    const __m128 dzero = _mm_cmpeq_ps(hi, _mm_setzero_ps());
    const int z = _mm_movemask_ps(dzero) & 7;
    if (z == 7) b4 = _mm_castsi128_ps(_mm_set1_epi32(-1));
    bad = _mm256_or_ps(bad, _mm256_castps128_ps256(_mm_and_ps(b4, _mm_castsi128_ps(_mm_set_epi32(0, 0, 0, -1)))));
  }
  return _mm256_movemask_ps(bad) == 0;
}
#endif

bool RaysLookValid(const RayRecord* rays, std::size_t b, std::size_t e)
{
#if defined(__x86_64__)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return RaysLookValidAvx2(rays, b, e);
#endif
  return RaysLookValidScalar(rays, b, e);
}

// A numpy array that owns a vector's buffer (moved in, never copied).
template <class T, class V>
nb::ndarray<nb::numpy, T> Own(std::vector<V>&& v, std::initializer_list<std::size_t> shape)
{
  auto* heap = new std::vector<V>(std::move(v));
  nb::capsule owner(heap, [](void* p) noexcept { delete static_cast<std::vector<V>*>(p); });
  return nb::ndarray<nb::numpy, T>(reinterpret_cast<T*>(heap->data()), shape, owner);
}

RaySpan Rays(const RayArray& a) { return {reinterpret_cast<const RayRecord*>(a.data()), a.shape(0)}; }

struct PyScene {
  std::shared_ptr<Scene> scene;
};

// The fp64 reference of a scene, built once, on the first call that needs
// it (normals: the piece of a hit and its barycentrics or CSG side).
const ref::ReferenceTracer& ReferenceOf(const std::shared_ptr<const Scene>& scene)
{
  static std::mutex m;
  static std::vector<std::pair<std::weak_ptr<const Scene>, std::shared_ptr<ref::ReferenceTracer>>> cache;
  std::lock_guard<std::mutex> lock(m);
  for (auto it = cache.begin(); it != cache.end();) {
    if (it->first.expired()) {
      it = cache.erase(it);
      continue;
    }
    if (it->first.lock() == scene) return *it->second;
    ++it;
  }
  cache.emplace_back(scene, std::make_shared<ref::ReferenceTracer>(*scene));
  return *cache.back().second;
}

// One trace's answers: the .hits records, as the CLI writes them (the tracer
// writes them there: no conversion).
// Result buffers of a tracer's calls that were given back (their Hits
// collected): the next call of the same size writes into one, so a loop of
// intersect calls does not fault in fresh pages each time, as the CLI's
// repeats reuse their buffer.
struct BufferPool {
  std::mutex m;
  std::vector<std::vector<HitRecord>> free;
  std::vector<HitRecord> Take(std::size_t n)
  {
    std::lock_guard<std::mutex> lock(m);
    for (auto it = free.begin(); it != free.end(); ++it)
      if (it->size() == n) {
        std::vector<HitRecord> v = std::move(*it);
        free.erase(it);
        return v;
      }
    return {};
  }
  void Give(std::vector<HitRecord>&& v)
  {
    if (v.size() < 4096) return;
    std::lock_guard<std::mutex> lock(m);
    if (free.size() >= 2) free.erase(free.begin());
    free.push_back(std::move(v));
  }
};

struct PyHits {
  PyHits() = default;
  PyHits(PyHits&&) = default;
  PyHits& operator=(PyHits&&) = default;
  ~PyHits()
  {
    if (pool) pool->Give(std::move(records));
  }
  std::shared_ptr<const Scene> scene;
  std::shared_ptr<BufferPool> pool;
  std::vector<HitRecord> records;  // FORMATS.md form
  // The caller's arrays (referenced, not copied): hit points for normals.
  std::optional<RayArray> rays;
  std::optional<TimeArray> times;
  bool occlusion = false;
  std::optional<std::vector<float>> normals;  // (N, 3), computed on first use
};

struct PyTracer {
  std::shared_ptr<const Scene> scene;
  std::unique_ptr<Tracer> tracer;
  std::unique_ptr<tbb::task_arena> arena;
  TraceConfig config;
  TraceStatsSum stats;
  const void* lastInput = nullptr;  // where the last call read its rays (tests check it is the caller's array)
  std::shared_ptr<BufferPool> pool = std::make_shared<BufferPool>();

  template <class F>
  void Run(F&& f)
  {
    if (arena) arena->execute(f);
    else f();
  }
};

// Into `out` (a fresh PyHits, or one of the same size to reuse: no new
// pages, as the CLI's repeats reuse theirs).
void TraceInto(PyTracer& t, const RayArray& rays, std::optional<TimeArray> times, bool occlusion, PyHits& out)
{
  out.scene = t.scene;
  out.pool = t.pool;
  out.normals.reset();
  out.occlusion = occlusion;
  if (out.records.size() != rays.shape(0)) out.records = t.pool->Take(rays.shape(0));
  const RaySpan span = Rays(rays);
  TimeSpan tspan;
  if (times) tspan = TimeSpan(times->data(), times->shape(0));
  t.lastInput = span.data();
  {
    nb::gil_scoped_release release;
    t.Run([&] { t.tracer->Trace(span, tspan, out.records, occlusion, t.config.stats ? &t.stats : nullptr); });
  }
  out.rays = rays;
  out.times = times;
}

PyHits Trace(PyTracer& t, const RayArray& rays, std::optional<TimeArray> times, bool occlusion)
{
  PyHits out;
  TraceInto(t, rays, times, occlusion, out);
  return out;
}

// A view of one 4-byte field of every record.
template <class T>
nb::ndarray<nb::numpy, T, nb::ndim<1>> Field(nb::handle self, const std::vector<HitRecord>& recs, std::size_t offset)
{
  const std::size_t n = recs.size();
  const int64_t stride = int64_t(sizeof(HitRecord) / sizeof(float));
  const char* base = reinterpret_cast<const char*>(recs.data()) + offset;
  return nb::ndarray<nb::numpy, T, nb::ndim<1>>(reinterpret_cast<T*>(const_cast<char*>(base)), 1, &n, self, &stride);
}

template <class T, std::size_t kOffset>
nb::ndarray<nb::numpy, T, nb::ndim<1>> FieldOf(nb::handle self)
{
  return Field<T>(self, nb::cast<const PyHits&>(self).records, kOffset);
}

AccelParams ParamsFrom(const nb::dict& d)
{
  AccelParams p;
  for (auto [k, v] : d) {
    const std::string key = nb::cast<std::string>(k);
    bool known = false;
    // CR_ACCEL_PARAMS field names in snake case: gridDensity -> grid_density.
#define CR_PY_PARAM(f, T, opt, help)                                        \
  {                                                                         \
    std::string snake;                                                      \
    for (char c : std::string(#f)) {                                        \
      if (c >= 'A' && c <= 'Z') snake += '_', snake += char(c - 'A' + 'a'); \
      else snake += c;                                                      \
    }                                                                       \
    if (key == snake) {                                                     \
      T val{};                                                              \
      if (!nb::try_cast<T>(v, val))                                         \
        throw nb::type_error(("structure parameter '" + key + "': expected " + \
                              (std::is_arithmetic_v<T> ? "a number" : "a string")).c_str()); \
      if constexpr (std::is_arithmetic_v<T>)                                \
        if (!(val >= T(0)))                                                 \
          throw InputError(fmt::format("structure parameter '{}' = {}: must be >= 0 (0: the default)", key, val)); \
      p.f = val;                                                            \
      known = true;                                                         \
    }                                                                       \
  }
    CR_ACCEL_PARAMS(CR_PY_PARAM)
#undef CR_PY_PARAM
    if (!known) {
      // The structure parameters' names, from the same list.
      std::string names;
#define CR_PY_PARAM_NAME(f, T, opt, help) names += std::string(names.empty() ? "" : ", ") + (opt + 2);
      CR_ACCEL_PARAMS(CR_PY_PARAM_NAME)
#undef CR_PY_PARAM_NAME
      for (char& c : names)
        if (c == '-') c = '_';
      throw nb::type_error(("tracer() got an unexpected keyword argument '" + key + "' (structure parameters: " +
                            names + ")")
                               .c_str());
    }
  }
  return p;
}

nb::dict CheckDict(const ref::CheckResult& c)
{
  nb::dict d;
  d["rays"] = c.rays;
  d["agree"] = c.agree;
  d["ties"] = c.ties;
  d["flips"] = c.flips;
  d["wrong"] = c.wrong;
  d["wrong_missed"] = c.wrongMissed;
  d["wrong_farther"] = c.wrongFarther;
  d["wrong_not_on_prim"] = c.wrongNotOnPrim;
  d["max_rel_t_error"] = c.maxRelTErr;
  d["mean_rel_t_error"] = c.meanRelTErr;
  d["first_wrong"] = c.firstWrong;
  d["first_wrong_why"] = c.firstWrongWhy;
  return d;
}

}  // namespace

NB_MODULE(_cellray, m)
{
  m.doc() = "cellray's native module (use the cellray package)";
  nb::register_exception_translator([](const std::exception_ptr& p, void*) {
    try {
      std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const RuntimeError& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError, "cellray: out of memory");
    }
  });

  nb::class_<PyScene>(m, "Scene")
      .def_static("load", [](const std::string& path) { return PyScene{std::make_shared<Scene>(LoadScene(path))}; })
      .def_static(
          "from_arrays",
          [](nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu> v,
             nb::ndarray<const std::int64_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu> tri,
             nb::ndarray<const double, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu> sph) {
            auto s = std::make_shared<Scene>();
            s->path = "<arrays>";
            s->materials.push_back(Material{});
            const std::size_t nv = v.shape(0);
            for (std::size_t i = 0; i < tri.shape(0); ++i) {
              std::vector<glm::dvec3> verts;
              for (int k = 0; k < 3; ++k) {
                const std::int64_t j = tri(i, k);
                if (j < 0 || std::size_t(j) >= nv)
                  throw InputError(fmt::format("triangles[{}]: vertex index {} is not in 0..{}", i, j, nv - 1));
                verts.emplace_back(v(std::size_t(j), 0), v(std::size_t(j), 1), v(std::size_t(j), 2));
              }
              AddPolygon(*s, PrimKind::kFace, verts, nullptr, 0, std::uint32_t(i + 1), s->path, false);
            }
            for (std::size_t i = 0; i < sph.shape(0); ++i) {
              PrimInfo info;
              info.type = CR_PRIM_SPHERE;
              info.line = std::uint32_t(i + 1);
              if (sph(i, 3) > 0.0) {
                info.nPieces = 1;
                info.firstPiece = s->AddPiece(
                    Sphere{{float(sph(i, 0)), float(sph(i, 1)), float(sph(i, 2))}, float(sph(i, 3))}, s->NumPrims());
              }
              s->prims.push_back(info);
            }
            return PyScene{s};
          },
          "vertices"_a, "triangles"_a, "spheres"_a)
      .def("_set_camera",
           [](PyScene& s, std::vector<double> eye, std::vector<double> at, std::vector<double> up, double fov, int w,
              int h) {
             Camera& c = s.scene->camera;
             c.from = glm::vec3(float(eye[0]), float(eye[1]), float(eye[2]));
             c.at = glm::vec3(float(at[0]), float(at[1]), float(at[2]));
             c.up = glm::vec3(float(up[0]), float(up[1]), float(up[2]));
             c.angle = float(fov);
             c.width = w;
             c.height = h;
             s.scene->hasCamera = true;
           })
      .def("_add_light",
           [](PyScene& s, std::vector<double> p, std::vector<double> c) {
             s.scene->lights.push_back(Light{glm::vec3(float(p[0]), float(p[1]), float(p[2])),
                                             glm::vec3(float(c[0]), float(c[1]), float(c[2]))});
           })
      .def_prop_ro("path", [](const PyScene& s) { return s.scene->path; })
      .def_prop_ro("num_prims", [](const PyScene& s) { return s.scene->NumPrims(); })
      .def_prop_ro("num_pieces", [](const PyScene& s) { return s.scene->NumUnified(); })
      .def_prop_ro("has_motion", [](const PyScene& s) { return s.scene->hasMotion; })
      .def_prop_ro("counts",
                   [](const PyScene& s) {
                     nb::dict d;
                     s.scene->ForEachType([&](const auto& a, std::uint32_t k) {
                       static const char* names[] = {"spheres", "triangles", "cones", "boxes",
                                                     "quadrics", "polyhedra", "sdfs", "csgs"};
                       d[names[k]] = a.size();
                     });
                     return d;
                   })
      .def_prop_ro("bounds",
                   [](const PyScene& s) {
                     const Bounds b = s.scene->WorldBounds();
                     return std::make_pair(std::vector<float>{b.lo.x, b.lo.y, b.lo.z},
                                           std::vector<float>{b.hi.x, b.hi.y, b.hi.z});
                   })
      .def_prop_ro("camera",
                   [](const PyScene& s) {
                     const Camera& c = s.scene->camera;
                     nb::dict d;
                     d["eye"] = std::vector<float>{c.from.x, c.from.y, c.from.z};
                     d["at"] = std::vector<float>{c.at.x, c.at.y, c.at.z};
                     d["up"] = std::vector<float>{c.up.x, c.up.y, c.up.z};
                     d["fov"] = c.angle;
                     d["width"] = c.width;
                     d["height"] = c.height;
                     d["aperture"] = c.aperture;
                     d["focal_distance"] = c.focal;
                     return d;
                   })
      .def_prop_ro("lights",
                   [](const PyScene& s) {
                     nb::list l;
                     for (const Light& li : s.scene->lights) {
                       nb::dict d;
                       d["position"] = std::vector<float>{li.position.x, li.position.y, li.position.z};
                       d["color"] = std::vector<float>{li.color.x, li.color.y, li.color.z};
                       l.append(d);
                     }
                     return l;
                   })
      .def(
          "_rays",
          [](const PyScene& s, const std::string& kind, int width, int height, bool spd, std::uint64_t seed,
             std::uint64_t count) {
            RayGenOptions g;
            g.kind = ParseRayKind(kind);
            g.width = width;
            g.height = height;
            g.spdCorners = spd;
            g.seed = seed;
            g.count = count;
            std::vector<float> times;
            std::vector<RayRecord> rays;
            {
              nb::gil_scoped_release release;
              ref::ReferenceTracer ref(*s.scene);
              rays = GenerateRays(*s.scene, ref, g, &times);
            }
            const std::size_t n = rays.size();
            if (times.empty()) times.assign(n, 0.0f);
            return std::make_pair(Own<float>(std::move(rays), {n, 8}), Own<float>(std::move(times), {n}));
          },
          "kind"_a, "width"_a, "height"_a, "spd_corners"_a, "seed"_a, "count"_a)
      .def(
          "_render",
          [](const PyScene& s, const std::string& accel, const std::string& backend, const std::string& precision,
             int threads, int width, int height, int spp, const std::string& integrator, int depth, bool spd,
             std::uint64_t seed, const std::string& diffuse, double areaLights, bool fresnel, const std::string& sides) {
            std::shared_ptr<Scene> scene = s.scene;
            if (areaLights > 0.0) {
              scene = std::make_shared<Scene>(*s.scene);
              PointLightsToSpheres(*scene, areaLights);
            }
            TracerOptions o;
            o.accel = accel;
            o.backend = backend;
            o.precision = precision;
            o.threads = threads;
            TraceConfig cfg = o.ToConfig();
            cfg.unifiedHits = true;
            RenderOptions ro;
            ro.width = width;
            ro.height = height;
            ro.spp = spp;
            if (integrator == "whitted") ro.integrator = Integrator::Whitted;
            else if (integrator == "path") ro.integrator = Integrator::Path;
            else throw InputError(fmt::format("integrator '{}': expected whitted or path", integrator));
            ro.maxDepth = depth > 0 ? depth : ro.integrator == Integrator::Path ? 8 : 5;
            ro.spd = spd;
            ro.seed = seed;
            ro.fresnel = fresnel;
            if (!diffuse.empty()) ro.diffuse = ParseDiffuse(diffuse);
            if (sides == "auto") ro.sides = Sides::Auto;
            else if (sides == "one") ro.sides = Sides::One;
            else if (sides == "two") ro.sides = Sides::Two;
            else throw InputError(fmt::format("sides '{}': expected auto, one or two", sides));
            ro.robustOffsets = cfg.backend != Backend::Embree && cfg.precision != Precision::Fast;
            Image img;
            {
              nb::gil_scoped_release release;
              std::unique_ptr<tbb::task_arena> arena;
              if (threads > 0) arena = std::make_unique<tbb::task_arena>(threads);
              auto run = [&] {
                auto tracer = CreateTracer(*scene, cfg);
                img = Render(*scene, *tracer, ro, nullptr);
              };
              if (arena) arena->execute(run);
              else run();
            }
            const std::size_t w = std::size_t(img.width), h = std::size_t(img.height);
            return Own<float>(std::move(img.rgb), {h, w, 3});
          },
          "accel"_a, "backend"_a, "precision"_a, "threads"_a, "width"_a, "height"_a, "spp"_a, "integrator"_a,
          "depth"_a, "spd"_a, "seed"_a, "diffuse"_a, "area_lights"_a, "fresnel"_a, "sides"_a);

  nb::class_<PyTracer>(m, "Tracer")
      .def(
          "__init__",
          [](PyTracer* t, const PyScene& s, const std::string& accel, const std::string& backend,
             const std::string& precision, std::optional<std::string> device, int threads,
             std::optional<std::string> variant, std::optional<std::string> isa, bool stats, const nb::dict& params) {
            new (t) PyTracer();
            t->scene = s.scene;
            TracerOptions o;
            o.accel = accel;
            o.backend = backend;
            o.precision = precision;
            o.threads = threads;
            o.device = device.value_or("");
            o.variant = variant.value_or("");
            o.isa = isa.value_or("");
            o.params = ParamsFrom(params);
            t->config = o.ToConfig();
            TraceConfig& c = t->config;
            c.stats = stats;
            c.unifiedHits = false;  // the .hits form, as `cellray trace` writes it
            if (threads < 0) throw InputError(fmt::format("threads {} is negative", threads));
            if (threads > 0) t->arena = std::make_unique<tbb::task_arena>(threads);
            nb::gil_scoped_release release;
            t->Run([&] { t->tracer = CreateTracer(*t->scene, c); });
          },
          "scene"_a, "accel"_a, "backend"_a, "precision"_a, "device"_a, "threads"_a, "variant"_a, "isa"_a, "stats"_a,
          "params"_a)
      .def("_trace",
           [](PyTracer& t, RayArray rays, std::optional<TimeArray> times, bool occlusion) {
             return Trace(t, rays, times, occlusion);
           },
           "rays"_a.noconvert(), "times"_a.noconvert().none(), "occlusion"_a)
      .def("_trace_into",
           [](PyTracer& t, RayArray rays, std::optional<TimeArray> times, bool occlusion, PyHits& out) {
             if (out.records.size() != rays.shape(0))
               throw nb::value_error(fmt::format("out: {} hits for {} rays (out= must come from a call with as many "
                                                 "rays)", out.records.size(), rays.shape(0)).c_str());
             TraceInto(t, rays, times, occlusion, out);
           },
           "rays"_a.noconvert(), "times"_a.noconvert().none(), "occlusion"_a, "out"_a)
      .def("_occluded",
           [](PyTracer& t, RayArray rays, std::optional<TimeArray> times) {
             PyHits h = Trace(t, rays, times, true);
             const std::size_t n = h.records.size();
             auto* flags = new std::vector<std::uint8_t>(n);
             for (std::size_t i = 0; i < n; ++i) (*flags)[i] = h.records[i].prim != CR_NO_HIT;
             nb::capsule owner(flags, [](void* p) noexcept { delete static_cast<std::vector<std::uint8_t>*>(p); });
             return nb::ndarray<nb::numpy, bool, nb::ndim<1>>(reinterpret_cast<bool*>(flags->data()), {n}, owner);
           },
           "rays"_a.noconvert(), "times"_a.noconvert().none())
      .def_prop_ro("_last_input_address", [](const PyTracer& t) { return std::uintptr_t(t.lastInput); })
      .def_prop_ro("backend", [](const PyTracer& t) { return std::string(BackendName(t.tracer->ActiveBackend())); })
      .def_prop_ro("accel", [](const PyTracer& t) { return std::string(AccelKindName(t.config.accel)); })
      .def_prop_ro("precision", [](const PyTracer& t) { return std::string(PrecisionName(t.config.precision)); })
      .def_prop_ro("device", [](const PyTracer& t) { return t.tracer->DeviceName(); })
      .def_prop_ro("variant", [](const PyTracer& t) { return t.tracer->VariantName(); })
      .def("stats", [](const PyTracer& t) {
        const AccelInfo& i = t.tracer->Info();
        nb::dict d;
        d["build_ms"] = i.buildMs;
        d["bytes"] = i.bytes;
        d["nodes"] = i.nodes;
        d["leaves"] = i.leaves;
        d["empty_leaves"] = i.emptyLeaves;
        d["refs"] = i.refs;
        d["params"] = i.params;
        d["rays"] = t.stats.rays;
        const double n = t.stats.rays ? double(t.stats.rays) : 1.0;
        if (t.config.stats) {
          d["intersection_tests"] = double(t.stats.nIT) / n;
          d["traversal_steps"] = double(t.stats.nTS) / n;
          d["leaves_visited"] = double(t.stats.nLeaves) / n;
          d["empty_leaves_visited"] = double(t.stats.nEmptyLeaves) / n;
        }
        return d;
      });

  nb::class_<PyHits>(m, "Hits")
      .def("__len__", [](const PyHits& h) { return h.records.size(); })
      .def_prop_ro("occlusion", [](const PyHits& h) { return h.occlusion; })
      // t, prim, u, v: views of one field of every record (prim: CR_NO_HIT
      // (0xFFFFFFFF) reads as -1).
      .def_prop_ro("t", &FieldOf<float, offsetof(HitRecord, t)>, nb::rv_policy::reference_internal)
      .def_prop_ro("prim", &FieldOf<std::int32_t, offsetof(HitRecord, prim)>, nb::rv_policy::reference_internal)
      .def_prop_ro("u", &FieldOf<float, offsetof(HitRecord, u)>, nb::rv_policy::reference_internal)
      .def_prop_ro("v", &FieldOf<float, offsetof(HitRecord, v)>, nb::rv_policy::reference_internal)
      .def_prop_ro("normal", [](nb::handle self) {
        PyHits& h = nb::cast<PyHits&>(self);
        const std::size_t n = h.records.size();
        if (!h.normals) {
          std::vector<float> out(n * 3, 0.0f);
          const RaySpan rays = Rays(*h.rays);
          {
            nb::gil_scoped_release release;
            const ref::ReferenceTracer& ref = ReferenceOf(h.scene);
            tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
              const HitRecord& rec = h.records[i];
              if (rec.prim == CR_NO_HIT || h.occlusion || rec.prim >= h.scene->NumPrims()) return;
              const RayRecord& r = rays[i];
              ref::DRay ray = ref::MakeRay(r);
              ray.time = h.times ? double(h.times->data()[i]) : 0.0;
              const glm::dvec3 p = ray.o + double(rec.t) * ray.d;
              // The piece hit (of a polygon's or patch's triangles, the one
              // with a root nearest the hit), with its barycentrics or a CSG
              // leaf's side, as the renderer's form would carry them.
              std::vector<std::uint32_t> pieces;
              ref.PiecesOf(rec.prim, pieces);
              std::uint32_t g = pieces.empty() ? CR_NO_HIT : pieces[0];
              double u = rec.u, v = rec.v, best = INFINITY;
              for (std::uint32_t piece : pieces) {
                double t[2], pu = 0.0, pv = 0.0;
                const int k = ref.PieceRoots(piece, ray, t, &pu, &pv);
                for (int j = 0; j < k && j < 1; ++j)
                  if (std::abs(t[j] - double(rec.t)) < best) best = std::abs(t[j] - double(rec.t)), g = piece, u = pu, v = pv;
              }
              if (g == CR_NO_HIT) return;
              const SurfacePoint sp = SurfaceAt(*h.scene, g, p, u, v, ray.time);
              for (int a = 0; a < 3; ++a) out[3 * i + std::size_t(a)] = sp.ng[a];
            });
          }
          h.normals = std::move(out);
        }
        const std::size_t shape[2] = {n, 3};
        return nb::ndarray<nb::numpy, float, nb::ndim<2>>(h.normals->data(), 2, shape, self);
      }, nb::rv_policy::reference_internal)
      .def("_records", [](nb::handle self) {
        // The raw records, (N, 4) uint32: the .hits file's payload.
        const PyHits& h = nb::cast<const PyHits&>(self);
        const std::size_t shape[2] = {h.records.size(), 4};
        return nb::ndarray<nb::numpy, std::uint32_t, nb::ndim<2>>(
            reinterpret_cast<std::uint32_t*>(const_cast<HitRecord*>(h.records.data())), 2, shape, self);
      }, nb::rv_policy::reference_internal);

  m.def(
      "_check",
      [](const PyScene& s, RayArray rays, std::optional<TimeArray> times, nb::ndarray<const std::uint32_t, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu> recs,
         bool occlusion) {
        if (recs.shape(0) != rays.shape(0))
          throw InputError(fmt::format("check: {} hits for {} rays", recs.shape(0), rays.shape(0)));
        const RaySpan span = Rays(rays);
        std::vector<RayRecord> rv(span.begin(), span.end());
        std::vector<HitRecord> hv(recs.shape(0));
        if (!hv.empty()) std::memcpy(hv.data(), recs.data(), hv.size() * sizeof(HitRecord));
        std::vector<float> tv;
        if (times) tv.assign(times->data(), times->data() + times->shape(0));
        ref::CheckResult c;
        {
          nb::gil_scoped_release release;
          ref::ReferenceTracer ref(*s.scene);
          c = ref::CheckHits(ref, rv, hv, occlusion, tv);
        }
        return CheckDict(c);
      },
      "scene"_a, "rays"_a.noconvert(), "times"_a.noconvert().none(), "records"_a.noconvert(), "occlusion"_a);

  m.def(
      "_validate_rays",
      [](RayArray rays) {
        const RaySpan span = Rays(rays);
        // In parallel, the quick test over blocks; in a failing block, the
        // first bad ray's message from ValidateRay (the .rays reader's rules).
        std::size_t first = span.size();
        {
          nb::gil_scoped_release release;
          first = tbb::parallel_reduce(
              tbb::blocked_range<std::size_t>(0, span.size(), 16384), span.size(),
              [&](const tbb::blocked_range<std::size_t>& r, std::size_t best) {
                if (r.begin() >= best || RaysLookValid(span.data(), r.begin(), r.end())) return best;
                for (std::size_t i = r.begin(); i != r.end() && i < best; ++i)
                  if (!ValidateRay(span[i]).empty()) return i;
                return best;
              },
              [](std::size_t x, std::size_t y) { return std::min(x, y); });
        }
        if (first < span.size()) throw InputError(fmt::format("rays[{}]: {}", first, ValidateRay(span[first])));
      },
      "rays"_a.noconvert());
  m.def(
      "_read_rays",
      [](const std::string& path) {
        std::vector<float> times;
        std::vector<RayRecord> rays = ReadRays(path, &times);
        const std::size_t n = rays.size();
        if (times.empty()) times.assign(n, 0.0f);
        return std::make_pair(Own<float>(std::move(rays), {n, 8}), Own<float>(std::move(times), {n}));
      },
      "path"_a);
  m.def(
      "_write_rays",
      [](const std::string& path, RayArray rays, std::optional<TimeArray> times) {
        const RaySpan span = Rays(rays);
        std::vector<float> tv;
        if (times) tv.assign(times->data(), times->data() + times->shape(0));
        WriteRays(path, std::vector<RayRecord>(span.begin(), span.end()), tv);
      },
      "path"_a, "rays"_a.noconvert(), "times"_a.noconvert().none());
  m.def(
      "_read_image",
      [](const std::string& path) {
        int w = 0, h = 0;
        std::vector<float> rgb = ReadImage(path, w, h);
        return Own<float>(std::move(rgb), {std::size_t(h), std::size_t(w), 3});
      },
      "path"_a);
  m.def(
      "_write_image",
      [](const std::string& path, nb::ndarray<const float, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu> img) {
        std::vector<float> rgb(img.data(), img.data() + img.size());
        WriteImage(path, int(img.shape(1)), int(img.shape(0)), rgb);
      },
      "path"_a, "image"_a.noconvert());
  m.def(
      "_read_hits",
      [](const std::string& path) {
        std::vector<HitRecord> h = ReadHits(path);
        const std::size_t n = h.size();
        return Own<std::uint32_t>(std::move(h), {n, 4});
      },
      "path"_a);
  m.def(
      "_write_hits",
      [](const std::string& path, nb::ndarray<const std::uint32_t, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu> recs) {
        std::vector<HitRecord> hv(recs.shape(0));
        if (!hv.empty()) std::memcpy(hv.data(), recs.data(), hv.size() * sizeof(HitRecord));
        WriteHits(path, hv);
      },
      "path"_a, "records"_a.noconvert());
}
