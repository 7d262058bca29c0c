// The `embree` backend: Intel's Embree 3 as the bench's baseline, tracing the
// same .rays as our backends with the same parallelism (oneTBB parallel_for
// over blocks of rays). Variants: `single` (rtcIntersect1 / rtcOccluded1 per
// ray), `packet8` (rtcIntersect8 / rtcOccluded8 on 8 consecutive rays) and,
// where Embree has native 16-wide packets (AVX-512), `packet16`;
// a `-robust` suffix builds the scene with RTC_SCENE_FLAG_ROBUST. The build
// quality is Embree's default (medium). Geometry: embree_scene.h. Motion
// blur: each ray's time goes to Embree (RTCRay::time), which interpolates the
// scene's two time steps (embree_scene.h).
// Hits are mapped to our HitRecord (scene-file ids, or unified indices for
// the renderer), so `check` and `bench` judge Embree like any backend.
#ifdef CELLRAY_HAVE_EMBREE

#include <atomic>
#include <cmath>
#include <type_traits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "host/core/error.h"
#include "host/embree/embree_scene.h"
#include "host/trace/tracer.h"

namespace cr {

namespace {

using embree::EmbreeScene;
using embree::OccluderContext;

// Embree's ray packets: the structure and the two calls of one width.
template <class RayHitT, void (*kIntersect)(const int*, RTCScene, RTCIntersectContext*, RayHitT*),
          void (*kOccluded)(const int*, RTCScene, RTCIntersectContext*, decltype(RayHitT::ray)*)>
struct EmbreePacketOf {
  using RayHit = RayHitT;
  static constexpr auto Intersect = kIntersect;
  static constexpr auto Occluded = kOccluded;
};
template <int W>
using EmbreePacket = std::conditional_t<W == 16, EmbreePacketOf<RTCRayHit16, rtcIntersect16, rtcOccluded16>,
                                        EmbreePacketOf<RTCRayHit8, rtcIntersect8, rtcOccluded8>>;

class EmbreeTracer final : public Tracer {
 public:
  EmbreeTracer(const Scene& scene, const TraceConfig& cfg)
      : scene_(scene), ranges_(scene.Ranges()), unified_(cfg.unifiedHits), primIds_(scene.UnifiedIds())
  {
    std::string v = cfg.variant;
    const std::string suffix = "-robust";
    if (v.size() >= suffix.size() && v.compare(v.size() - suffix.size(), suffix.size(), suffix) == 0) {
      robust_ = true;
      v.resize(v.size() - suffix.size());
    }
    if (v.empty() || v == "single" || v == "ray")
      packet_ = 0;
    else if (v == "packet8" || v == "packet")
      packet_ = 8;
    else if (v == "packet16")
      packet_ = 16;
    else
      throw InputError(fmt::format("--variant '{}': the embree backend has single, packet8 and packet16 (each also "
                                   "with -robust: RTC_SCENE_FLAG_ROBUST)",
                                   cfg.variant));
    if (cfg.accel != AccelKind::BVH)
      throw InputError(fmt::format("--backend embree builds Embree's own BVH; --accel {} is not available",
                                   AccelKindName(cfg.accel)));
    if (cfg.precision != Precision::Robust)
      throw InputError(fmt::format("--backend embree has Embree's own arithmetic; --precision {} applies to our "
                                   "backends (--variant single-robust selects RTC_SCENE_FLAG_ROBUST)",
                                   PrecisionName(cfg.precision)));
    if (cfg.stats) throw InputError("--backend embree: Embree does not count Havran's measures (drop --stats)");
    embree::EmbreeOptions opt;
    opt.robust = robust_;
    es_ = std::make_unique<EmbreeScene>(scene, opt);
    if (packet_ == 8 && !rtcGetDeviceProperty(es_->Device(), RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED))
      throw InputError("--variant packet8: this Embree or CPU has no 8-wide ray packets (AVX)");
    if (packet_ == 16 && !rtcGetDeviceProperty(es_->Device(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED))
      throw InputError("--variant packet16: this Embree or CPU has no 16-wide ray packets (AVX-512)");
    info_.buildMs = es_->BuildMs();
    info_.bytes = es_->Bytes();
    info_.params = fmt::format("embree {} build=medium flags={}", RTC_VERSION_STRING, robust_ ? "robust" : "none");
  }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum*) override
  {
    hits.resize(rays.size());
    if (packet_) {
      const std::size_t w = static_cast<std::size_t>(packet_);
      const std::size_t nPackets = (rays.size() + w - 1) / w;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nPackets, 128 / w), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t p = r.begin(); p != r.end(); ++p)
          if (packet_ == 16)
            TracePacket<16>(rays, times, hits, p * w, occlusion);
          else
            TracePacket<8>(rays, times, hits, p * w, occlusion);
      });
    } else {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) hits[i] = TraceOne(rays[i], TimeOf(times, i), occlusion);
      });
    }
  }

  std::string DeviceName() const override { return "cpu (Embree " RTC_VERSION_STRING ")"; }
  std::string VariantName() const override
  {
    return fmt::format("{}{}", packet_ ? fmt::format("packet{}", packet_) : "single", robust_ ? " robust" : "");
  }
  void Describe(nlohmann::json& j) const override
  {
    j["embree_version"] = RTC_VERSION_STRING;
    j["embree_occluder_lookups"] = occluderLookups_.load();
  }

 private:
  const Scene& scene_;
  PrimRanges ranges_{};
  bool unified_ = false;
  int packet_ = 0;  // rays per packet: 0 (single), 8 or 16
  bool robust_ = false;
  std::vector<std::uint32_t> primIds_;
  std::unique_ptr<EmbreeScene> es_;
  // Occluded rays whose occluder the filter did not record (looked up with
  // a closest-hit query instead); expected to stay 0 but for CSG solids,
  // whose occluding leaf is looked up so.
  mutable std::atomic<std::uint64_t> occluderLookups_{0};

  // Ray i's time in the shutter interval (0 without times).
  static float TimeOf(TimeSpan times, std::size_t i) { return times.empty() ? 0.0f : times[i]; }

  static void SetRay(RTCRay& r, const RayRecord& rec, float time)
  {
    r.org_x = rec.org[0];
    r.org_y = rec.org[1];
    r.org_z = rec.org[2];
    r.tnear = rec.tmin;
    r.dir_x = rec.dir[0];
    r.dir_y = rec.dir[1];
    r.dir_z = rec.dir[2];
    r.time = time;
    r.tfar = rec.tmax;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
  }

  void InitContext(OccluderContext& c, std::uint32_t* occluder, unsigned lanes) const
  {
    rtcInitIntersectContext(&c.ctx);
    c.base = es_->Base();
    c.occluder = occluder;
    c.lanes = lanes;
  }

  // Our record of a hit on Embree's geometry geomID, primitive primID.
  HitRecord Record(unsigned geomID, unsigned primID, float t, float u, float v, bool occlusion) const
  {
    if (geomID == RTC_INVALID_GEOMETRY_ID) return HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
    return RecordOfUnified(es_->Base()[geomID] + primID, t, u, v, occlusion);
  }

  HitRecord RecordOfUnified(std::uint32_t g, float t, float u, float v, bool occlusion) const
  {
    HitRecord h{occlusion ? 0.0f : t, unified_ ? g : primIds_[g], 0.0f, 0.0f};
    if (Prim_Is(&ranges_, CR_PRIM_CSG, g)) {  // the leaf (kernels/csg.h)
      if (unified_) {
        h.u = u;
        h.v = v;
      } else {
        h.prim += static_cast<std::uint32_t>(u);
      }
      return h;
    }
    if (!occlusion && Prim_Is(&ranges_, CR_PRIM_TRIANGLE, g) &&
        (unified_ || (scene_.triangles[Prim_Local(&ranges_, CR_PRIM_TRIANGLE, g)].flags & CR_TRI_REPORT_UV))) {
      h.u = u;
      h.v = v;
    }
    return h;
  }

  HitRecord Closest(const RayRecord& rec, float time) const
  {
    OccluderContext c;
    InitContext(c, nullptr, 0);
    RTCRayHit rh;
    SetRay(rh.ray, rec, time);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(es_->Handle(), &c.ctx, &rh);
    return Record(rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v, false);
  }

  // An occluded ray whose occluder was not recorded: any hit is an occluder.
  HitRecord LookUpOccluder(const RayRecord& rec, float time) const
  {
    ++occluderLookups_;
    HitRecord h = Closest(rec, time);
    if (h.prim != CR_NO_HIT) h.t = 0.0f;
    return h;
  }

  HitRecord TraceOne(const RayRecord& rec, float time, bool occlusion) const
  {
    if (!occlusion) return Closest(rec, time);
    std::uint32_t occluder = CR_NO_HIT;
    OccluderContext c;
    InitContext(c, &occluder, 1);
    RTCRay r;
    SetRay(r, rec, time);
    rtcOccluded1(es_->Handle(), &c.ctx, &r);
    if (!(r.tfar < 0.0f)) return HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
    if (occluder == CR_NO_HIT) return LookUpOccluder(rec, time);
    return RecordOfUnified(occluder, 0.0f, 0.0f, 0.0f, true);
  }

  template <int W>
  void TracePacket(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
                   std::size_t first, bool occlusion) const
  {
    constexpr std::size_t kPacket = W;
    const std::size_t n = std::min(kPacket, rays.size() - first);
    alignas(64) int valid[kPacket];
    alignas(64) typename EmbreePacket<W>::RayHit rh;
    for (std::size_t i = 0; i < kPacket; ++i) {
      const std::size_t j = first + (i < n ? i : 0);
      const RayRecord& rec = rays[j];
      valid[i] = i < n ? -1 : 0;
      rh.ray.org_x[i] = rec.org[0];
      rh.ray.org_y[i] = rec.org[1];
      rh.ray.org_z[i] = rec.org[2];
      rh.ray.tnear[i] = rec.tmin;
      rh.ray.dir_x[i] = rec.dir[0];
      rh.ray.dir_y[i] = rec.dir[1];
      rh.ray.dir_z[i] = rec.dir[2];
      rh.ray.time[i] = TimeOf(times, j);
      rh.ray.tfar[i] = rec.tmax;
      rh.ray.mask[i] = 0xFFFFFFFFu;
      rh.ray.id[i] = static_cast<unsigned>(i);
      rh.ray.flags[i] = 0;
      rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    std::uint32_t occluder[kPacket];
    for (auto& o : occluder) o = CR_NO_HIT;
    OccluderContext c;
    InitContext(c, occluder, kPacket);
    if (!occlusion) {
      EmbreePacket<W>::Intersect(valid, es_->Handle(), &c.ctx, &rh);
      for (std::size_t i = 0; i < n; ++i)
        hits[first + i] = Record(rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i], rh.hit.u[i], rh.hit.v[i], false);
      return;
    }
    EmbreePacket<W>::Occluded(valid, es_->Handle(), &c.ctx, &rh.ray);
    for (std::size_t i = 0; i < n; ++i) {
      if (!(rh.ray.tfar[i] < 0.0f))
        hits[first + i] = HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
      else if (occluder[i] == CR_NO_HIT)
        hits[first + i] = LookUpOccluder(rays[first + i], TimeOf(times, first + i));
      else
        hits[first + i] = RecordOfUnified(occluder[i], 0.0f, 0.0f, 0.0f, true);
    }
  }
};

}  // namespace

std::unique_ptr<Tracer> CreateEmbreeTracer(const Scene& scene, const TraceConfig& config)
{
  return std::make_unique<EmbreeTracer>(scene, config);
}

}  // namespace cr

#endif  // CELLRAY_HAVE_EMBREE
