// Cheap look at a ray set before tracing it: are consecutive rays coherent
// enough for packets? (The `auto` variant of the SIMD backend.)
#pragma once

#include <span>
#include <cstddef>
#include <vector>

#include "kernels/types.h"

namespace cr::simd {

struct CoherenceSample {
  std::size_t groups = 0;    // groups of `width` consecutive rays looked at
  std::size_t coherent = 0;  // of which all directions lie within a narrow angle
  double Fraction() const { return groups ? double(coherent) / double(groups) : 0.0; }
};

// Looks at up to `maxGroups` groups of `width` consecutive rays spread over
// the set. A group is coherent when every direction is within `cosLimit` (the
// cosine of that half angle) of the group's first direction and shares
// its octant, which is what lets a packet's lanes take the same BVH path.
CoherenceSample SampleCoherence(std::span<const RayRecord> rays, int width, std::size_t maxGroups = 512,
                                double cosLimit = 0.99);

}  // namespace cr::simd
