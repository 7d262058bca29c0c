// One row of a bench run: a configuration tracing one ray set of one scene,
// with its structure, timing, Havran's measures and its error against the
// fp64 reference. Serialised to results.json as one record per row.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "host/bench/bench_options.h"

namespace cr::bench {

struct Timing {
  double medianMs = 0.0, minMs = 0.0, maxMs = 0.0;
  int repeat = 0;
  // The kernels' device time (Tracer::LastKernelMs) of the same runs; a
  // negative median where the backend reports none.
  double kernelMedianMs = -1.0, kernelMinMs = -1.0, kernelMaxMs = -1.0;
};

struct PerRay {
  double nIT = 0.0, nTS = 0.0, nLeaves = 0.0, nEmptyLeaves = 0.0;
};

struct ErrorSummary {
  std::uint64_t agree = 0, ties = 0, flips = 0, wrong = 0;
  double maxRelTErr = 0.0, meanRelTErr = 0.0;
};

struct Row {
  std::string scene, scenePath;
  std::uint64_t prims = 0;   // geometry statements (primitive ids)
  std::uint64_t pieces = 0;  // unified primitives (triangles of split polygons count one each)
  RayKind kind = RayKind::Primary;
  std::uint64_t rays = 0;
  Combo combo;
  std::string variantRan;  // Tracer::VariantName after tracing
  std::string device;
  int threads = 0;
  AccelInfo structure;
  Timing timing;
  bool interleaved = false;  // timed in rounds over the scene's rows (BenchOptions::interleave)
  std::optional<PerRay> perRay;  // absent where the backend has no counters (Embree)
  std::optional<ErrorSummary> error;
  std::uint64_t hits = 0;  // rays answered with a hit (occluded, for shadow rays)
  // Process peak since this configuration's build began, less what the
  // scene's earlier configurations still hold under interleaved timing
  // (0: unknown).
  std::uint64_t peakRssBytes = 0;
  std::string note;        // e.g. why a row was skipped
};

void to_json(nlohmann::json& j, const Row& r);

}  // namespace cr::bench
