#ifdef CELLRAY_HAVE_EMBREE

#include "host/embree/embree_scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <type_traits>

#include <fmt/format.h>

#include "host/core/error.h"
#include "kernels/types.h"

// Our float tests (kernels/, robust mode) for the user geometries: the same
// arithmetic as the scalar backend's.
namespace cr::embree_kernels {
#include "kernels/intersect.h"
}  // namespace cr::embree_kernels

namespace cr::embree {

// User data of a user geometry: its primitives in place and their boxes.
struct UserGeometry {
  const void* prims = nullptr;
  std::vector<RTCBounds> bounds;
};

namespace {

// The kernels' uniform test of each type, by overload.
#define CR_EMBREE_TEST_(T, U, a)                                                                                 \
  inline int KernelTest(const embree_kernels::Ray* r, const T* p, float tmin, float tmax, float* t, float* u, float* v) \
  {                                                                                                              \
    return embree_kernels::T##_Test(r, p, tmin, tmax, t, u, v);                                                 \
  }
CR_PRIM_TYPES(CR_EMBREE_TEST_)
#undef CR_EMBREE_TEST_

const char* ErrorName(RTCError code)
{
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "error";
}

void UserBounds(const RTCBoundsFunctionArguments* args)
{
  const auto* user = static_cast<const UserGeometry*>(args->geometryUserPtr);
  *args->bounds_o = user->bounds[args->primID];
}

// Lane i of a packet (N = 1 for rtcIntersect1) as the kernels' Ray: only the
// origin and direction are read by the tests.
embree_kernels::Ray LaneRay(RTCRayN* ray, unsigned N, unsigned i)
{
  embree_kernels::Ray r{};
  r.org[0] = RTCRayN_org_x(ray, N, i);
  r.org[1] = RTCRayN_org_y(ray, N, i);
  r.org[2] = RTCRayN_org_z(ray, N, i);
  r.dir[0] = RTCRayN_dir_x(ray, N, i);
  r.dir[1] = RTCRayN_dir_y(ray, N, i);
  r.dir[2] = RTCRayN_dir_z(ray, N, i);
  return r;
}

template <class T>
void UserIntersect(const RTCIntersectFunctionNArguments* args)
{
  const auto* user = static_cast<const UserGeometry*>(args->geometryUserPtr);
  const T prim = static_cast<const T*>(user->prims)[args->primID];
  const unsigned N = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, N);
  for (unsigned i = 0; i < N; ++i) {
    if (args->valid[i] != -1) continue;
    const embree_kernels::Ray r = LaneRay(ray, N, i);
    float t = 0.0f, u = 0.0f, v = 0.0f;
    if (!KernelTest(&r, &prim, RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i), &t, &u, &v)) continue;
    RTCRayN_tfar(ray, N, i) = t;
    RTCHitN_geomID(hit, N, i) = args->geomID;
    RTCHitN_primID(hit, N, i) = args->primID;
    RTCHitN_u(hit, N, i) = u;
    RTCHitN_v(hit, N, i) = v;
    // The geometric normal is not used by the bench or the renderer's
    // embree path (hits are mapped back to our primitives).
    RTCHitN_Ng_x(hit, N, i) = 0.0f;
    RTCHitN_Ng_y(hit, N, i) = 0.0f;
    RTCHitN_Ng_z(hit, N, i) = 1.0f;
    RTCHitN_instID(hit, N, i, 0) = args->context->instID[0];
  }
}

template <class T>
void UserOccluded(const RTCOccludedFunctionNArguments* args)
{
  const auto* user = static_cast<const UserGeometry*>(args->geometryUserPtr);
  const T prim = static_cast<const T*>(user->prims)[args->primID];
  auto* octx = reinterpret_cast<OccluderContext*>(args->context);
  const unsigned N = args->N;
  for (unsigned i = 0; i < N; ++i) {
    if (args->valid[i] != -1) continue;
    const embree_kernels::Ray r = LaneRay(args->ray, N, i);
    float t = 0.0f, u = 0.0f, v = 0.0f;
    if (!KernelTest(&r, &prim, RTCRayN_tnear(args->ray, N, i), RTCRayN_tfar(args->ray, N, i), &t, &u, &v)) continue;
    RTCRayN_tfar(args->ray, N, i) = -INFINITY;
    // A CSG solid's occluder is the leaf its first crossing names: left
    // unrecorded, the tracer looks it up with a closest-hit query.
    if constexpr (std::is_same_v<T, Csg>) continue;
    if (i < octx->lanes && octx->occluder[i] == CR_NO_HIT) octx->occluder[i] = octx->base[args->geomID] + args->primID;
  }
}

// Occlusion filter of the native geometries: accepts the hit and records its
// primitive for the lane (Embree calls callbacks with the packet size and
// lane order of the query, rtcOccluded4/8/16(3)).
void RecordOccluder(const RTCFilterFunctionNArguments* args)
{
  auto* octx = reinterpret_cast<OccluderContext*>(args->context);
  const unsigned N = args->N;
  for (unsigned i = 0; i < N && i < octx->lanes; ++i) {
    if (args->valid[i] == 0 || octx->occluder[i] != CR_NO_HIT) continue;
    octx->occluder[i] = octx->base[RTCHitN_geomID(args->hit, N, i)] + RTCHitN_primID(args->hit, N, i);
  }
}

}  // namespace

bool EmbreeScene::Monitor(void* self, ssize_t bytes, bool)
{
  static_cast<EmbreeScene*>(self)->monitored_.fetch_add(static_cast<std::int64_t>(bytes), std::memory_order_relaxed);
  return true;
}

void EmbreeScene::OnError(void* self, RTCError code, const char* message)
{
  static_cast<EmbreeScene*>(self)->lastError_ = fmt::format("{}{}{}", ErrorName(code), message ? ": " : "",
                                                            message ? message : "");
}

void EmbreeScene::ThrowIfFailed(const char* what)
{
  const RTCError code = rtcGetDeviceError(device_);
  if (code == RTC_ERROR_NONE) return;
  throw RuntimeError(fmt::format("Embree: {}: {}", what, lastError_.empty() ? ErrorName(code) : lastError_));
}

EmbreeScene::EmbreeScene(const Scene& scene, const EmbreeOptions& options)
{
  const auto t0 = std::chrono::steady_clock::now();
  // No "threads=" here: Embree 3 built with TBB schedules its build on the
  // process's TBB arena, so `--threads` (a tbb::global_control) limits it
  // like our own builders.
  device_ = rtcNewDevice("verbose=0");
  if (!device_) throw RuntimeError(fmt::format("Embree: cannot create a device ({})", ErrorName(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(device_, &EmbreeScene::OnError, this);
  rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeScene::Monitor, this);
  try {
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);  // Embree's default
    const PrimRanges r = scene.Ranges();
    std::uint32_t geomID = 0;
    auto attach = [&](RTCGeometry geom, std::uint32_t base, const char* what) {
      rtcCommitGeometry(geom);
      const unsigned id = rtcAttachGeometry(scene_, geom);
      rtcReleaseGeometry(geom);
      ThrowIfFailed(what);
      if (id != geomID) throw RuntimeError(fmt::format("Embree: geometry id {} where {} was expected", id, geomID));
      base_.push_back(base);
      ++geomID;
    };
    scene.ForEachType([&](const auto& pieces, std::uint32_t k) {
      using T = typename std::decay_t<decltype(pieces)>::value_type;
      const auto n = static_cast<unsigned>(pieces.size());
      if (n == 0) return;
      if constexpr (std::is_same_v<T, Sphere>) {
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        // Sphere is {centre[3], radius}: Embree's FLOAT4 point layout as is.
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, pieces.data(), 0, sizeof(Sphere), n);
        rtcSetGeometryOccludedFilterFunction(g, &RecordOccluder);
        attach(g, r.begin[k], "sphere geometry");
      } else if constexpr (std::is_same_v<T, Triangle>) {
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Triangle holds v0, v1, v2 each in 16 bytes (xyz and a 4-byte field):
        // a vertex buffer of stride 16 read in place, vertex 3i + k being vk of
        // piece i; the last vertex is followed by its pad, so Embree's 16-byte
        // loads stay inside the array.
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, pieces.data(), 0, 16,
                                   std::size_t(n) * 3);
        indices_.resize(std::size_t(n) * 3);
        for (std::size_t i = 0; i < indices_.size(); ++i) indices_[i] = static_cast<std::uint32_t>(i);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0,
                                   3 * sizeof(std::uint32_t), n);
        rtcSetGeometryOccludedFilterFunction(g, &RecordOccluder);
        attach(g, r.begin[k], "triangle geometry");
      } else {
        auto user = std::make_unique<UserGeometry>();
        user->prims = pieces.data();
        user->bounds.resize(n);
        for (std::uint32_t i = 0; i < n; ++i) {
          const Bounds b = scene.UnifiedBounds(r.begin[k] + i);
          // A few ulps of slack: the float test may report a point a rounding
          // error outside the exact surface's box.
          const float pad = 1e-6f * std::max({std::fabs(b.lo.x), std::fabs(b.lo.y), std::fabs(b.lo.z),
                                              std::fabs(b.hi.x), std::fabs(b.hi.y), std::fabs(b.hi.z), 1e-30f});
          user->bounds[i] = RTCBounds{b.lo.x - pad, b.lo.y - pad, b.lo.z - pad, 0.0f,
                                      b.hi.x + pad, b.hi.y + pad, b.hi.z + pad, 0.0f};
        }
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, n);
        rtcSetGeometryUserData(g, user.get());
        rtcSetGeometryBoundsFunction(g, &UserBounds, nullptr);
        rtcSetGeometryIntersectFunction(g, &UserIntersect<T>);
        rtcSetGeometryOccludedFunction(g, &UserOccluded<T>);
        users_.push_back(std::move(user));
        attach(g, r.begin[k], "user geometry");
      }
    });
    empty_ = geomID == 0;
    rtcCommitScene(scene_);
    ThrowIfFailed("scene commit");
  } catch (...) {
    if (scene_) rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
    throw;
  }
  buildMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::int64_t held = monitored_.load();
  bytes_ = std::uint64_t(held > 0 ? held : 0) + indices_.size() * sizeof(std::uint32_t);
}

EmbreeScene::~EmbreeScene()
{
  rtcReleaseScene(scene_);
  rtcReleaseDevice(device_);
}

}  // namespace cr::embree

#endif  // CELLRAY_HAVE_EMBREE
