// A cellray scene as an Embree 3 scene, for the `embree` baseline backend
// (embree_tracer.cpp). Compiled only when the build found Embree
// (CELLRAY_HAVE_EMBREE).
//
// Geometry, one Embree geometry per primitive type, in the order of the
// unified index g (kernels/types.h), so that g = base[geomID] + primID:
//  - triangles natively (RTC_GEOMETRY_TYPE_TRIANGLE), every piece of a split
//    polygon or patch being one triangle; Embree's barycentrics u, v have the
//    meaning of ours (u weights v1, v weights v2);
//  - spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT (Embree's ray-sphere test);
//  - every other type (kernels/types.h CR_PRIM_TYPES) as user geometry that
//    calls our own float test, Type_Test in robust mode (kernels/<type>.h):
//    Embree's own shapes beyond these two are not ours (its curves are
//    swept circles along a spline, for one).
// Motion blur (a scene with `motion`): Embree's own, every geometry with two
// time steps, at rest and moved (static pieces: equal steps); Embree
// interpolates vertices (triangles, sphere centres) and the user geometries'
// boxes linearly at the ray's time, and the user geometries' tests shift the
// ray into the piece's rest frame as our kernels do (kernels/motion.h).
// Occlusion queries must report *some* occluder (FORMATS.md), which Embree's
// rtcOccluded does not: an occlusion filter on each geometry records the
// first accepted hit's g in the query context (OccluderContext).
#pragma once

#ifdef CELLRAY_HAVE_EMBREE

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include "host/scene/scene.h"

namespace cr::embree {

// The intersect context of our queries: Embree hands the RTCIntersectContext
// pointer back to every callback, so fields after it travel with the query.
struct OccluderContext {
  RTCIntersectContext ctx;    // must stay the first member
  const std::uint32_t* base;  // unified index of primID 0, per geomID
  std::uint32_t* occluder;    // per packet lane: g of an occluder, CR_NO_HIT if none yet
  unsigned lanes;             // entries of occluder
};

struct UserGeometry;

struct EmbreeOptions {
  bool robust = false;  // RTC_SCENE_FLAG_ROBUST (Embree's watertight, slower mode)
};

// Owns the device and the committed scene. Reads the Scene's primitive arrays
// in place (shared buffers): the Scene must outlive it.
class EmbreeScene {
 public:
  EmbreeScene(const Scene& scene, const EmbreeOptions& options);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RTCDevice Device() const { return device_; }
  RTCScene Handle() const { return scene_; }
  const std::uint32_t* Base() const { return base_.data(); }
  // Bytes Embree held after the commit (memory monitor: its BVH, including
  // its leaf copies of the triangles), plus our index buffer.
  std::uint64_t Bytes() const { return bytes_; }
  double BuildMs() const { return buildMs_; }
  bool Empty() const { return empty_; }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<std::uint32_t> base_;      // by geomID
  std::vector<std::uint32_t> indices_;   // triangle index buffer (3 per piece)
  // Motion blur only (empty for a static scene): the unified motion array
  // (Scene::UnifiedMotion) the user geometries' tests read, and the time
  // step 1 vertex buffers of the native geometries (pieces moved).
  std::vector<float> motion_;
  std::vector<Triangle> movedTriangles_;
  std::vector<Sphere> movedSpheres_;
  std::vector<std::unique_ptr<UserGeometry>> users_;  // user data of the user geometries
  std::atomic<std::int64_t> monitored_{0};
  std::uint64_t bytes_ = 0;
  double buildMs_ = 0.0;
  bool empty_ = true;

  std::string lastError_;  // message of Embree's error callback

  static bool Monitor(void* self, ssize_t bytes, bool post);
  static void OnError(void* self, RTCError code, const char* message);
  void ThrowIfFailed(const char* what);
};

}  // namespace cr::embree

#endif  // CELLRAY_HAVE_EMBREE
