// `cellray check`: compares a hit file (ours or any tracer's) with the fp64
// reference, ray by ray, and adjudicates disagreements in double precision.
//
// Tolerance (docs/TOLERANCE.md has the derivation). A float tracer's answer
// is judged against the exact geometry up to a perturbation of the ray, in
// world units, of
//   delta(t) = 2^-16 (|o|_inf + t |d|_inf)
// at the point o + t d: about 128 float ulps of the magnitudes the ray and its
// hit work with (|o|, the distance travelled, and so the hit point's own
// magnitude, |o + t d| <= |o| + t |d|). It belongs to the ray and its hit
// only: neither the scene's extent nor the primitive's size enters it, so one
// huge primitive cannot widen the tolerance of any answer. An answer is
//  - agree: the same primitive as the reference, |t - t_ref| |d| <= delta;
//  - tie:   both hit, different primitives or a t off by more than delta, but
//           explained within delta: the reported point lies within delta of
//           the reported primitive and every surface the ray meets before it
//           is marginal (a delta-shifted ray misses it, or it lies within
//           delta of tmin/tmax);
//  - flip:  one side hits and the other misses (closest: a hit against a
//           miss; occlusion: occluded against free), explained within delta:
//           every surface the reference finds on the ray is marginal, or the
//           reported primitive comes within delta of the ray. Flips are
//           counted apart: neither agree nor tie ever absorbs one;
//  - wrong: anything else (a robust nearer surface skipped, a point not on
//           the primitive it names, a robust hit reported as a miss, a hit
//           reported where the ray passes the surface by more than delta).
// Occlusion answers: "occluded by P" agrees if P meets the ray in
// [tmin, tmax] and the reference finds the ray occluded; "free" agrees if the
// reference finds nothing.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/types.h"
#include "host/reference/reference.h"

namespace cr::ref {

inline constexpr double kCheckRelTol = 0x1p-16;

// delta(t) of the tolerance above for a ray with |o|_inf = oMax and
// |d|_inf = dMax (t < 0 or not finite counts as 0).
inline double CheckDelta(double oMax, double dMax, double t)
{
  const double tt = t > 0.0 && t < INFINITY ? t : 0.0;
  return kCheckRelTol * (oMax + tt * dMax);
}

struct CheckResult {
  std::uint64_t rays = 0;
  std::uint64_t agree = 0;
  std::uint64_t ties = 0;
  std::uint64_t flips = 0;          // hit/miss disagreements explained within delta (never in agree or ties)
  std::uint64_t wrong = 0;
  std::uint64_t wrongMissed = 0;    // reported a miss (or free) past a robust surface
  std::uint64_t wrongFarther = 0;   // reported a hit behind a robust nearer surface
  std::uint64_t wrongNotOnPrim = 0; // reported point/primitive not a real intersection
  double maxRelTErr = 0.0;          // over agreeing closest hits
  double meanRelTErr = 0.0;
  std::vector<std::uint64_t> firstWrong;  // up to 16 indices
  std::vector<std::string> firstWrongWhy;
};

// Verdict for one ray; relErr set for agreeing closest hits.
enum class Verdict { Agree, Tie, Flip, WrongMissed, WrongFarther, WrongNotOnPrim };
inline bool IsWrong(Verdict v) { return v != Verdict::Agree && v != Verdict::Tie && v != Verdict::Flip; }
// With a time: the ray at that time in the shutter interval (motion blur;
// each primitive is judged in its own frame, ReferenceTracer::Framed).
Verdict Adjudicate(const ReferenceTracer& tracer, const RayRecord& ray, const HitRecord& hit, bool occlusion,
                   double* relErr, std::vector<RefHit>& scratch);
Verdict Adjudicate(const ReferenceTracer& tracer, const RayRecord& ray, float time, const HitRecord& hit,
                   bool occlusion, double* relErr, std::vector<RefHit>& scratch);

// times: empty (every ray at time 0) or one per ray.
CheckResult CheckHits(const ReferenceTracer& tracer, const std::vector<RayRecord>& rays,
                      const std::vector<HitRecord>& hits, bool occlusion,
                      const std::vector<float>& times = std::vector<float>());

}  // namespace cr::ref
