#ifdef CELLRAY_HAVE_EMBREE

#include "host/embree/embree_scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <type_traits>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "kernels/types.h"

// Our float tests (kernels/, robust mode) for the user geometries: the same
// arithmetic as the scalar backend's.
namespace cr::embree_kernels {
#include "kernels/intersect.h"
}  // namespace cr::embree_kernels

namespace cr::embree {

// User data of a user geometry: its primitives in place and their boxes,
// per time step (bounds[step * count + primID]); in a scene with motion, the
// unified motion array and the unified index of primID 0, for the ray's shift
// into a piece's rest frame (kernels/motion.h).
struct UserGeometry {
  const void* prims = nullptr;
  unsigned count = 0;
  std::vector<RTCBounds> bounds;
  const float* motion = nullptr;  // null for a static scene
  std::uint32_t base = 0;
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
  *args->bounds_o = user->bounds[std::size_t(args->timeStep) * user->count + args->primID];
}

// Lane i of a packet (N = 1 for rtcIntersect1) as the kernels' Ray as piece
// primID of `user` sees it: only the origin and direction are read by the
// tests; a moving piece's ray has its origin shifted by -time * motion, as
// our backends shift it (kernels/motion.h Motion_Shift).
embree_kernels::Ray LaneRay(RTCRayN* ray, unsigned N, unsigned i, const UserGeometry* user, unsigned primID)
{
  embree_kernels::Ray r{};
  r.org[0] = RTCRayN_org_x(ray, N, i);
  r.org[1] = RTCRayN_org_y(ray, N, i);
  r.org[2] = RTCRayN_org_z(ray, N, i);
  r.dir[0] = RTCRayN_dir_x(ray, N, i);
  r.dir[1] = RTCRayN_dir_y(ray, N, i);
  r.dir[2] = RTCRayN_dir_z(ray, N, i);
  if (!user->motion) return r;
  r.time = RTCRayN_time(ray, N, i);
  embree_kernels::Ray moved;
  return embree_kernels::Motion_Shift(user->motion, user->base + primID, &r, &moved) ? moved : r;
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
    const embree_kernels::Ray r = LaneRay(ray, N, i, user, args->primID);
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
    const embree_kernels::Ray r = LaneRay(args->ray, N, i, user, args->primID);
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
    // Motion blur (kernels/motion.h): in a scene with motion every geometry
    // has two time steps, the pieces at rest (time 0) and moved by their
    // motion (time 1), static pieces alike (equal steps); Embree
    // interpolates linearly between them at the ray's time, which for a
    // translation is the piece at that time. A static scene keeps one step.
    motion_ = scene.UnifiedMotion();
    const bool moving = scene.hasMotion;
    const unsigned steps = moving ? 2u : 1u;
    auto motionOf = [&](std::uint32_t g) {
      return glm::vec3(motion_[4 * std::size_t(g)], motion_[4 * std::size_t(g) + 1], motion_[4 * std::size_t(g) + 2]);
    };
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
        if (moving) rtcSetGeometryTimeStepCount(g, 2);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, pieces.data(), 0, sizeof(Sphere), n);
        if (moving) {  // time step 1: the centres moved
          movedSpheres_.assign(pieces.begin(), pieces.end());
          for (std::uint32_t i = 0; i < n; ++i) {
            const glm::vec3 m = motionOf(r.begin[k] + i);
            for (int a = 0; a < 3; ++a) movedSpheres_[i].center[a] += m[a];
          }
          rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 1, RTC_FORMAT_FLOAT4, movedSpheres_.data(), 0,
                                     sizeof(Sphere), n);
        }
        rtcSetGeometryOccludedFilterFunction(g, &RecordOccluder);
        attach(g, r.begin[k], "sphere geometry");
      } else if constexpr (std::is_same_v<T, Triangle>) {
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (moving) rtcSetGeometryTimeStepCount(g, 2);
        // Triangle holds v0, v1, v2 each in 16 bytes (xyz and a 4-byte field):
        // a vertex buffer of stride 16 read in place, vertex 3i + k being vk of
        // piece i; the last vertex is followed by its pad, so Embree's 16-byte
        // loads stay inside the array.
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, pieces.data(), 0, 16,
                                   std::size_t(n) * 3);
        if (moving) {  // time step 1: the vertices moved, in the same layout
          movedTriangles_.assign(pieces.begin(), pieces.end());
          for (std::uint32_t i = 0; i < n; ++i) {
            const glm::vec3 m = motionOf(r.begin[k] + i);
            Triangle& t = movedTriangles_[i];
            for (int a = 0; a < 3; ++a) {
              t.v0[a] += m[a];
              t.v1[a] += m[a];
              t.v2[a] += m[a];
            }
          }
          rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 1, RTC_FORMAT_FLOAT3, movedTriangles_.data(), 0, 16,
                                     std::size_t(n) * 3);
        }
        indices_.resize(std::size_t(n) * 3);
        for (std::size_t i = 0; i < indices_.size(); ++i) indices_[i] = static_cast<std::uint32_t>(i);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0,
                                   3 * sizeof(std::uint32_t), n);
        rtcSetGeometryOccludedFilterFunction(g, &RecordOccluder);
        attach(g, r.begin[k], "triangle geometry");
      } else {
        auto user = std::make_unique<UserGeometry>();
        user->prims = pieces.data();
        user->count = n;
        user->bounds.resize(std::size_t(steps) * n);
        if (moving) {
          user->motion = motion_.data();
          user->base = r.begin[k];
        }
        for (std::uint32_t i = 0; i < n; ++i) {
          // The box at rest (time step 0) and, with motion, moved (step 1):
          // Embree bounds the piece at time tau by the two boxes linearly
          // interpolated, which for a translation is the box at tau.
          Bounds b[2];
          b[0] = FloatBounds(pieces[i]);
          b[1] = b[0];
          if (moving) {
            const glm::vec3 m = motionOf(r.begin[k] + i);
            for (int a = 0; a < 3; ++a) {
              b[1].lo[a] = FloatDown(double(b[0].lo[a]) + double(m[a]));
              b[1].hi[a] = FloatUp(double(b[0].hi[a]) + double(m[a]));
            }
          }
          // A few ulps of slack: the float test may report a point a rounding
          // error outside the exact surface's box (one slack for both steps).
          float scale = 1e-30f;
          for (unsigned s = 0; s < steps; ++s)
            scale = std::max({scale, std::fabs(b[s].lo.x), std::fabs(b[s].lo.y), std::fabs(b[s].lo.z),
                              std::fabs(b[s].hi.x), std::fabs(b[s].hi.y), std::fabs(b[s].hi.z)});
          const float pad = 1e-6f * scale;
          for (unsigned s = 0; s < steps; ++s)
            user->bounds[std::size_t(s) * n + i] =
                RTCBounds{b[s].lo.x - pad, b[s].lo.y - pad, b[s].lo.z - pad, 0.0f,
                          b[s].hi.x + pad, b[s].hi.y + pad, b[s].hi.z + pad, 0.0f};
        }
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
        if (moving) rtcSetGeometryTimeStepCount(g, 2);
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
  bytes_ = std::uint64_t(held > 0 ? held : 0) + indices_.size() * sizeof(std::uint32_t) +
           movedTriangles_.size() * sizeof(Triangle) + movedSpheres_.size() * sizeof(Sphere) +
           motion_.size() * sizeof(float);
}

EmbreeScene::~EmbreeScene()
{
  rtcReleaseScene(scene_);
  rtcReleaseDevice(device_);
}

}  // namespace cr::embree

#endif  // CELLRAY_HAVE_EMBREE
