// Sums of Havran's per-ray measures over a batch, one struct for every
// backend (the per-ray device layout is TraceStats, kernels/types.h). Plain
// data: AddStats is defined once in tracer.cpp, so no ISA unit of the SIMD
// backend emits it.
#pragma once

#include <cstdint>

namespace cr {

struct TraceStatsSum {
  std::uint64_t rays = 0;
  std::uint64_t nIT = 0;
  std::uint64_t nTS = 0;
  std::uint64_t nLeaves = 0;
  std::uint64_t nEmptyLeaves = 0;
};

void AddStats(TraceStatsSum& sum, const TraceStatsSum& s);

}  // namespace cr
