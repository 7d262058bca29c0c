// The hypercube paper's data-parallel bands (render --distribute bands-data,
// docs/DISTRIBUTED.md). Rank r renders the image rows of its band and holds
// a structure over only the primitives that can lie in its band's volume;
// a ray that leaves the volume before it has found its hit is passed on.
//
// Volumes: the planes through the eye that contain the camera's right
// vector and a row boundary between two bands cut all of space into
// wedges about the eye's horizontal line (the axis). Wedge r holds the
// elevation angles of rank r's rows, the first and last wedges reaching
// round behind the eye to meet there, so the wedges are a ring that covers
// every point: this is the rule for secondary rays, which need no extra
// primitives. A primitive belongs to every wedge its bounding box (moving
// ones: swept over the shutter, padded by 1e-3 of its distance from the
// eye) meets. Seen along the axis, a ray's elevation angle turns one way
// only and by less than half a turn, so a ray crosses a run of neighbouring
// wedges in order.
//
// Tracing: each rank traces the rays in its wedge against its own
// structure, over the ray's whole interval. The ray keeps the nearest hit
// found so far; it ends where that hit lies before the ray leaves the
// current wedge (no primitive of a later wedge can be nearer), or in the
// last wedge of its run; otherwise it is passed, in the round's batch, to
// the rank of the next wedge. A shadow ray ends at its first blocker or in
// its last wedge. The answer goes back to the ray's own rank, which shades
// it: the pixel sums are formed there in one process's order, so the image
// is the single-process image bit for bit (the paper's shadow subtraction
// becomes the blocked answer returned for a shadow ray that was provisionally
// lit). Rounds are collective (every rank takes part in every round);
// Finish() serves the other ranks once this rank's own rays are done.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/trace/tracer.h"

namespace cr {

// The ring of wedges: eye, forward and up of the camera, and the elevation
// angle of each band's upper boundary (upper[0] = pi, upper[n] = -pi; rank
// r's wedge is (upper[r + 1], upper[r]]).
struct BandWedges {
  glm::dvec3 eye{0.0}, forward{0.0, 0.0, -1.0}, up{0.0, 1.0, 0.0};
  std::vector<double> upper;
  std::vector<glm::dvec2> unit;  // (cos, sin) of each upper angle
  int Count() const { return int(upper.size()) - 1; }
  // Wedges of `n` bands of a width x height image, band r holding rows
  // [h r / n, h (r + 1) / n) (the bands of --distribute bands).
  static BandWedges ForRows(const CameraFrame& frame, int n);
  glm::dvec2 Project(const glm::dvec3& p) const;  // (along forward, along up) from the eye
  int WedgeOf(double angle) const;
  // The wedge of a projected point q != 0 (the same as WedgeOf its angle,
  // by cross products instead of atan2; the inner boundaries lie in front of
  // the eye, within a quarter turn of forward).
  int WedgeOfPoint(const glm::dvec2& q) const;
  // Whether the wedges of a box (its padded projection) include wedge r.
  std::vector<bool> WedgesOfBox(const Bounds& box) const;
  // The run of wedges a ray crosses over [tmin, tmax]: the first, the
  // direction (-1: towards wedge 0, elevation rising; +1: away) and how many
  // more; wedge k of the run is At(run, k).
  struct Run {
    int start = 0, step = 1, hops = 0;
  };
  Run RunOf(const RayRecord& ray) const;
  int At(const Run& run, int k) const { return int(((std::int64_t(run.start) + std::int64_t(k) * run.step) % Count() + Count()) % Count()); }
  // Where the ray leaves wedge k of its run (tmax in the last), not before
  // tPrev, where it left wedge k - 1.
  double Exit(const RayRecord& ray, const Run& run, int k, double tPrev) const;
};

// What one rank's band did (the heuristic table of docs/DISTRIBUTED.md).
struct BandStats {
  std::uint64_t ownRays = 0, ownShadowRays = 0;      // rays this rank's render traced
  std::uint64_t leftRays = 0, leftShadowRays = 0;    // of those, rays answered by another rank too
  std::uint64_t forwarded = 0, answered = 0;         // rays passed on / answers sent to other ranks
  std::uint64_t received = 0;                        // rays other ranks passed here
  std::uint64_t rounds = 0;
  std::uint64_t localPieces = 0, totalPieces = 0;    // pieces in this rank's structure / the scene
  std::uint64_t structureBytes = 0;
  double traceMs = 0.0, exchangeMs = 0.0, serveMs = 0.0;
};
void to_json(nlohmann::json& j, const BandStats& s);

class BandTracer : public Tracer {
 public:
  // Collective: every rank builds its own structure (config's backend and
  // accel) over the pieces of its wedge.
  BandTracer(const Scene& scene, const TraceConfig& config, const BandWedges& wedges);
  ~BandTracer() override;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override;
  using Tracer::Trace;
  // Collective: serves other ranks' rays until every rank has called it.
  void Finish();
  std::string DeviceName() const override;
  std::string VariantName() const override;
  Backend ActiveBackend() const override;
  std::string FallbackReason() const override;
  const BandStats& Stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  BandStats stats_;
};

}  // namespace cr
