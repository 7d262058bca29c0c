// `cellray check`: compares a hit file (ours or any tracer's) with the fp64
// reference, ray by ray, and adjudicates disagreements in double precision.
//
// Tolerance. A float tracer's answer is judged against the exact geometry up
// to a perturbation, in world units, of
//   delta = 2^-16 * (|o|_inf + t |d|_inf) + 2^-19 * S
// where S is the largest coordinate magnitude of the primitive involved
// (vertices; centre or axis ends plus radius): about 500 float ulps of the
// magnitudes the ray works with, plus 16 ulps of the primitive's own (a float
// watertight test on a large triangle errs in proportion to its vertices,
// not to the hit point). An answer is
//  - agree: the same primitive as the reference, |t - t_ref| |d| <= delta;
//  - tie:   different, but explained within delta: the reported point lies
//           within delta of the reported primitive and every surface the ray
//           meets before it is marginal (a delta-shifted ray misses it, or it
//           lies within delta of tmin/tmax); or a reported miss where every
//           surface on the ray is marginal;
//  - wrong: anything else (a robust nearer surface skipped, a point not on
//           the primitive it names, a robust hit reported as a miss).
// Occlusion answers: "occluded by P" is right if P meets the ray in
// [tmin, tmax] (or a delta-shifted ray does, or P comes within delta of the
// ray there); "free" is right if every surface the ray meets there is
// marginal.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kernels/types.h"
#include "reference/reference.h"

namespace cr::ref {

inline constexpr double kCheckRelTol = 0x1p-16;
inline constexpr double kCheckPrimTol = 0x1p-19;

struct CheckResult {
  std::uint64_t rays = 0;
  std::uint64_t agree = 0;
  std::uint64_t ties = 0;
  std::uint64_t wrong = 0;
  std::uint64_t wrongMissed = 0;    // reported a miss (or free) past a robust surface
  std::uint64_t wrongFarther = 0;   // reported a hit behind a robust nearer surface
  std::uint64_t wrongNotOnPrim = 0; // reported point/primitive not a real intersection
  double maxRelTErr = 0.0;          // over agreeing closest hits
  double meanRelTErr = 0.0;
  std::vector<std::uint64_t> firstWrong;  // up to 16 indices
  std::vector<std::string> firstWrongWhy;
};

// Verdict for one ray: 0 agree, 1 tie, 2 wrong; relErr set for agreeing hits.
enum class Verdict { Agree, Tie, WrongMissed, WrongFarther, WrongNotOnPrim };
Verdict Adjudicate(const ReferenceTracer& tracer, const RayRecord& ray, const HitRecord& hit, bool occlusion,
                   double* relErr, std::vector<RefHit>& scratch);

CheckResult CheckHits(const ReferenceTracer& tracer, const std::vector<RayRecord>& rays,
                      const std::vector<HitRecord>& hits, bool occlusion);

}  // namespace cr::ref
