// The numerically hard cases (the "hard cases" issue): generated scenes and
// ray sets, each with an exact expectation per ray, run by the test suite
// (tests/hard/) and reported by RunHardSuite (tests/hard/gen/hard.h).
//
// A case is a named generator: a scene and rays produced by code from fixed
// seeds (no files), and the rule every answer must satisfy. The rules are
// stricter than `cellray check` where the case knows more than the checker:
// a ray from inside a closed mesh must hit (check.h would accept a miss
// through a vertex as a tie), a ray leaving a surface must not report that
// surface near its origin (check.h accepts such a point as marginal).
//
// "Wrong" counts rays: a ray is wrong when its closest-hit or its occlusion
// answer (whichever the case asks) breaks the rule. Every answer must also be
// well formed: no NaN in t, u, v; a miss is exactly (+inf, no id); a hit has
// a finite t and a valid id.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "host/accel/accel.h"
#include "kernels/types.h"
#include "host/scene/scene.h"
#include "host/trace/tracer.h"

namespace cr::ref {
class ReferenceTracer;
}

namespace cr::hard {

// The rule a case's answers must satisfy (besides being well formed).
enum class Expect {
  // Agree or tie with the fp64 reference (check.h Adjudicate).
  Reference,
  // Ray from strictly inside a closed convex mesh, which it crosses once, at
  // x* = o + t* d (the reference's first crossing). A hit (a miss is a
  // leak) naming a triangle that contains x* within check.h's delta(t*)
  // (a ray that slips through an edge and reports the far side fails
  // this), and, for closest hits, |t - t*| |d| <= delta(t*).
  Closed,
  // Per ray: target[i] is the id the closest hit must report (occlusion:
  // occluded), with t within relTolT of the reference's, |t - t*| <=
  // relTolT t*; CR_NO_HIT: a miss (both queries); kAnyPrim: as Reference.
  Target,
  // Grazing: Reference, and never a miss (the case encloses every ray in a
  // backstop, so something is always hit).
  Backstopped,
  // Secondary rays leaving primitive `target` (a surface point moved off by
  // scene/surface.h OffsetRayOrigin): Reference, and the ray's own primitive
  // is reported only where the reference meets it again away from the
  // origin: closest t >= ownT / 2, occlusion only if ownT <= tmax, ownT
  // being the reference's first root on that primitive beyond the offset
  // (INFINITY for a convex or flat surface left on its outer side).
  NotSelf,
};

const char* ExpectName(Expect e);

// Target: no particular id, the reference's answer.
inline constexpr std::uint32_t kAnyPrim = 0xFFFFFFFEu;

// How building the structure must go.
enum class BuildExpect {
  Ok,             // builds, no warning asked
  Warns,          // builds after a warning (a parameter clamped); answers judged
  ThrowsInput,    // InputError (bad parameter), never a crash
  ThrowsRuntime,  // RuntimeError (a limit), never a crash
};

struct HardCase {
  std::string name;  // "family/case", e.g. "leaks/icosphere"
  std::shared_ptr<const Scene> scene;
  AccelParams params;
  std::vector<AccelKind> accels;  // the structures it applies to (empty: all)
  std::vector<RayRecord> rays;
  Expect expect = Expect::Reference;
  std::vector<std::uint32_t> target;  // Target: expected id; NotSelf: the id the ray leaves
  std::vector<double> ownT;           // NotSelf: see above
  double relTolT = 0.0;               // Target: relative t tolerance (0: t not judged)
  bool closest = true;
  bool occlusion = true;
  BuildExpect build = BuildExpect::Ok;
  long generatorWarnings = 0;       // cr::WarningCount() growth while the scene was made
  long expectGeneratorWarnings = 0; // at least this many (degenerate input)
};

struct GenOptions {
  bool quick = false;  // reduced ray counts (CI)
};

// A named generator. `perAccel`: the rays are taken from the built structure
// (its cell planes), so the case is generated once per structure.
struct CaseSpec {
  std::string name;
  std::string family;
  std::string description;  // what it builds and what it expects (Markdown, one paragraph)
  bool perAccel = false;
  std::function<HardCase(AccelKind accel, const GenOptions& options)> make;
};

// Every case, in report order.
const std::vector<CaseSpec>& CaseSpecs();

// The reference's closest answer to every ray, computed once per case.
struct CaseReference {
  std::shared_ptr<const ref::ReferenceTracer> tracer;
  std::vector<double> t;           // closest t, INFINITY for a miss
  std::vector<std::uint32_t> prim;  // closest id, CR_NO_HIT for a miss
};
CaseReference ComputeReference(const HardCase& c);

// The verdict on one answer: empty when right, else why it is wrong.
std::string JudgeAnswer(const HardCase& c, const CaseReference& ref, std::size_t i, const HitRecord& hit,
                        bool occlusion);

// One run of a case on one tracer configuration.
struct CaseRun {
  std::uint64_t rays = 0;
  std::uint64_t wrong = 0;
  std::vector<std::string> firstWrong;  // up to 4: "ray 12 (closest): missed ..."
  std::string note;                     // build outcome, exception text
};
// Creates the tracer (checking the build expectation), traces the rays with
// the queries the case asks and judges every answer.
CaseRun RunCase(const HardCase& c, const CaseReference& ref, const TraceConfig& config);

}  // namespace cr::hard
