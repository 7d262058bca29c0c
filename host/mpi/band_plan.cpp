#include "host/mpi/band_plan.h"

#include <cmath>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

namespace cr {

void to_json(nlohmann::json& j, const BandPlan& p)
{
  j = nlohmann::json{{"ranks", p.ranks},     {"rays", p.rays},         {"shadow_rays", p.shadowRays},
                     {"trace_calls", p.traceCalls}, {"max_hops", p.maxHops}, {"started", p.started},
                     {"visits", p.visits}, {"passed", p.passed},     {"returned", p.returned},
                     {"pieces", p.pieces}};
}

BandPlanTracer::BandPlanTracer(const Scene& scene, std::unique_ptr<Tracer> inner, const CameraFrame& frame,
                               const std::vector<int>& ranks)
    : inner_(std::move(inner))
{
  info_ = inner_->Info();
  backend_ = inner_->ActiveBackend();
  const std::uint32_t n = scene.NumUnified();
  std::vector<Bounds> boxes(n);
  for (std::uint32_t g = 0; g < n; ++g) boxes[g] = scene.UnifiedBounds(g);
  for (int P : ranks) {
    BandPlan p;
    p.ranks = P;
    p.wedges = BandWedges::ForRows(frame, P);
    for (auto* v : {&p.started, &p.visits, &p.passed, &p.returned, &p.pieces}) v->assign(std::size_t(P), 0);
    for (const Bounds& b : boxes) {
      const std::vector<bool> in = p.wedges.WedgesOfBox(b);
      for (int r = 0; r < P; ++r) p.pieces[std::size_t(r)] += in[std::size_t(r)];
    }
    plans_.push_back(std::move(p));
  }
}

void BandPlanTracer::TraceRays(RaySpan rays, TimeSpan times,
                           std::vector<HitRecord>& hits, bool occlusion, TraceStatsSum* stats)
{
  TraceInRange(*inner_, rays, times, hits, occlusion, stats);
  const std::vector<HitRecord>* stop = &hits;
  if (occlusion) {
    // The nearest blocker, where the shadow ray's run stops.
    TraceInRange(*inner_, rays, times, nearest_, false, nullptr);
    stop = &nearest_;
  }
  for (BandPlan& p : plans_) {
    ++p.traceCalls;
    (occlusion ? p.shadowRays : p.rays) += rays.size();
    // Each ray's run and stop (in parallel), then the counts.
    std::vector<BandWedges::Run> run(rays.size());
    std::vector<int> last(rays.size());
    tbb::parallel_for(std::size_t(0), rays.size(), [&](std::size_t i) {
      const RayRecord& ray = rays[i];
      run[i] = p.wedges.RunOf(ray);
      const HitRecord& h = (*stop)[i];
      const double t = h.prim == CR_NO_HIT ? INFINITY : double(h.t);
      int k = 0;
      double prev = double(ray.tmin);
      while (k < run[i].hops) {
        const double e = p.wedges.Exit(ray, run[i], k, prev);
        if (t <= e) break;
        prev = e;
        ++k;
      }
      last[i] = k;
    });
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ++p.started[std::size_t(run[i].start)];
      for (int k = 0; k <= last[i]; ++k) ++p.visits[std::size_t(p.wedges.At(run[i], k))];
      for (int k = 0; k < last[i]; ++k) ++p.passed[std::size_t(p.wedges.At(run[i], k))];
      if (last[i] > 0) ++p.returned[std::size_t(p.wedges.At(run[i], last[i]))];
      p.maxHops = std::max<std::uint64_t>(p.maxHops, std::uint64_t(last[i]));
    }
  }
}

}  // namespace cr
