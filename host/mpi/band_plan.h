// The counts --distribute bands-data would see at any number of ranks,
// found in one process (render --band-plan 2,4,...,1024): for each rank
// count P, the wedges of P bands (host/mpi/band_tracer.h), and for every ray
// the render casts, the run of wedges it would visit before its answer is
// known. A closest-hit ray stops in the first wedge of its run that it
// leaves after its hit (the rule BandTracer follows); a shadow ray in the
// first that it leaves after its nearest blocker (BandTracer stops at the
// first blocker it finds, which lies in that wedge or, for a primitive held
// by several wedges, earlier). bench/mpi_simulate.py plans from these.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/mpi/band_tracer.h"

namespace cr {

struct BandPlan {
  int ranks = 0;
  BandWedges wedges;
  // Per wedge: rays whose run starts there, rays traced there (a run's every
  // wedge up to its stop), rays passed on from there, the answers that stop
  // there for a ray that started elsewhere; pieces held.
  std::vector<std::uint64_t> started, visits, passed, returned, pieces;
  std::uint64_t rays = 0, shadowRays = 0, traceCalls = 0, maxHops = 0;
};
void to_json(nlohmann::json& j, const BandPlan& p);

class BandPlanTracer : public Tracer {
 public:
  BandPlanTracer(const Scene& scene, std::unique_ptr<Tracer> inner, const CameraFrame& frame, const std::vector<int>& ranks);
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override;
  using Tracer::Trace;
  std::string DeviceName() const override { return inner_->DeviceName(); }
  std::string VariantName() const override { return inner_->VariantName(); }
  Backend ActiveBackend() const override { return inner_->ActiveBackend(); }
  std::string FallbackReason() const override { return inner_->FallbackReason(); }
  const std::vector<BandPlan>& Plans() const { return plans_; }

 private:
  std::unique_ptr<Tracer> inner_;
  std::vector<BandPlan> plans_;
  std::vector<HitRecord> nearest_;
};

}  // namespace cr
