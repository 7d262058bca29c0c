#include "host/bench/bench_row.h"

#include <nlohmann/json.hpp>

namespace cr::bench {

void to_json(nlohmann::json& j, const Row& r)
{
  auto rate = [&](double ms) { return ms > 0.0 ? double(r.rays) / (ms * 1e3) : 0.0; };
  j = nlohmann::json{{"scene", r.scene},
                     {"scene_path", r.scenePath},
                     {"prims", r.prims},
                     {"pieces", r.pieces},
                     {"kind", RayKindName(r.kind)},
                     {"query", IsOcclusionKind(r.kind) ? "occlusion" : "closest"},
                     {"rays", r.rays},
                     {"label", r.combo.Label()},
                     {"backend", BackendName(r.combo.backend)},
                     {"accel", r.combo.backend == Backend::Embree ? "embree-bvh" : AccelKindName(r.combo.accel)},
                     {"precision", r.combo.backend == Backend::Embree ? "embree" : PrecisionName(r.combo.precision)},
                     {"variant", r.combo.variant},
                     {"variant_ran", r.variantRan},
                     {"device", r.device},
                     {"threads", r.threads},
                     {"build_ms", r.structure.buildMs},
                     {"bytes", r.structure.bytes},
                     {"structure", r.structure},
                     {"hits", r.hits},
                     {"peak_rss_bytes", r.peakRssBytes},
                     {"note", r.note}};
  if (r.timing.repeat > 0) {
    j["trace_ms"] = {{"median", r.timing.medianMs}, {"min", r.timing.minMs}, {"max", r.timing.maxMs}};
    // The fastest run gives the highest rate.
    j["mrays_per_s"] = {{"median", rate(r.timing.medianMs)}, {"min", rate(r.timing.maxMs)}, {"max", rate(r.timing.minMs)}};
    j["repeat"] = r.timing.repeat;
    j["interleaved"] = r.interleaved;
    if (r.timing.kernelMedianMs >= 0.0) {
      j["kernel_ms"] = {{"median", r.timing.kernelMedianMs}, {"min", r.timing.kernelMinMs}, {"max", r.timing.kernelMaxMs}};
      j["kernel_mrays_per_s"] = {{"median", rate(r.timing.kernelMedianMs)}, {"min", rate(r.timing.kernelMaxMs)},
                                 {"max", rate(r.timing.kernelMinMs)}};
    } else {
      j["kernel_ms"] = nullptr;
      j["kernel_mrays_per_s"] = nullptr;
    }
  } else {
    j["trace_ms"] = nullptr;
    j["mrays_per_s"] = nullptr;
    j["repeat"] = 0;
  }
  if (r.perRay)
    j["per_ray"] = {{"intersection_tests", r.perRay->nIT},
                    {"traversal_steps", r.perRay->nTS},
                    {"leaves_visited", r.perRay->nLeaves},
                    {"empty_leaves_visited", r.perRay->nEmptyLeaves}};
  else
    j["per_ray"] = nullptr;
  if (r.error) {
    const double n = r.rays ? double(r.rays) : 1.0;
    j["error"] = {{"agree", r.error->agree},
                  {"ties", r.error->ties},
                  {"flips", r.error->flips},
                  {"wrong", r.error->wrong},
                  {"wrong_rate", double(r.error->wrong) / n},
                  {"max_rel_t_err", r.error->maxRelTErr},
                  {"mean_rel_t_err", r.error->meanRelTErr}};
  } else {
    j["error"] = nullptr;
  }
}

}  // namespace cr::bench
