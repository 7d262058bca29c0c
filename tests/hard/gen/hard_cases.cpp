#include "tests/hard/gen/hard_cases.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "tests/hard/gen/hard_gen.h"
#include "host/core/error.h"
#include "host/reference/check.h"
#include "host/reference/reference.h"

namespace cr::hard {

const char* ExpectName(Expect e)
{
  switch (e) {
    case Expect::Reference: return "reference";
    case Expect::Closed: return "closed";
    case Expect::Target: return "target";
    case Expect::Backstopped: return "backstopped";
    case Expect::NotSelf: return "not-self";
  }
  return "?";
}

const std::vector<CaseSpec>& CaseSpecs()
{
  static const std::vector<CaseSpec> specs = [] {
    std::vector<CaseSpec> s;
    AddLeakCases(s);
    AddCellCases(s);
    AddAxisCases(s);
    AddTinyFarCases(s);
    AddGrazingCases(s);
    AddSelfCases(s);
    AddHugeCases(s);
    AddSdfCases(s);
    AddCsgCases(s);
    AddDegenerateCases(s);
    AddExtremeCases(s);
    return s;
  }();
  return specs;
}

CaseReference ComputeReference(const HardCase& c)
{
  CaseReference r;
  r.tracer = std::make_shared<const ref::ReferenceTracer>(*c.scene);
  const std::size_t n = c.rays.size();
  r.t.assign(n, INFINITY);
  r.prim.assign(n, CR_NO_HIT);
  const Scene& scene = *c.scene;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& br) {
    for (std::size_t i = br.begin(); i != br.end(); ++i) {
      const ref::RefHit h = r.tracer->Intersect(ref::MakeRay(c.rays[i]));
      if (h.Found()) {
        r.t[i] = h.t;
        r.prim[i] = scene.IdOfUnified(h.g);
      }
    }
  });
  return r;
}

namespace {

double MaxAbs3(const float* v)
{
  return std::max(std::fabs(double(v[0])), std::max(std::fabs(double(v[1])), std::fabs(double(v[2]))));
}

// check.h's delta for the point at t on the ray.
double Delta(const RayRecord& r, double t) { return ref::CheckDelta(MaxAbs3(r.org), MaxAbs3(r.dir), t); }

double Length(const float* d) { return std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]); }

// Empty when the record is well formed.
std::string WellFormed(const Scene& scene, const HitRecord& h, bool occlusion)
{
  if (std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v)) return "NaN in the answer";
  if (h.prim == CR_NO_HIT) return h.t == INFINITY ? "" : fmt::format("a miss with t = {}", h.t);
  if (h.prim >= scene.NumPrims()) return fmt::format("id {} out of range", h.prim);
  if (occlusion ? h.t != 0.0f : !std::isfinite(h.t)) return fmt::format("a hit with t = {}", h.t);
  if (!std::isfinite(h.u) || !std::isfinite(h.v)) return "u, v not finite";
  return "";
}

std::string Describe(const HitRecord& h, const CaseReference& ref, std::size_t i)
{
  return fmt::format("got (t {}, id {}), reference (t {}, id {})", h.t, h.prim == CR_NO_HIT ? -1L : long(h.prim),
                     ref.t[i], ref.prim[i] == CR_NO_HIT ? -1L : long(ref.prim[i]));
}

// Agree or tie with the reference (with the cheap agreeing case first).
std::string ReferenceVerdict(const HardCase& c, const CaseReference& ref, std::size_t i, const HitRecord& h,
                             bool occlusion)
{
  const RayRecord& r = c.rays[i];
  if (!occlusion && h.prim == ref.prim[i]) {
    if (h.prim == CR_NO_HIT) return "";
    if (std::fabs(double(h.t) - ref.t[i]) * Length(r.dir) <= Delta(r, ref.t[i])) return "";
  }
  thread_local std::vector<ref::RefHit> scratch;
  double relErr = 0.0;
  switch (ref::Adjudicate(*ref.tracer, r, h, occlusion, &relErr, scratch)) {
    case ref::Verdict::Agree:
    case ref::Verdict::Tie:
    case ref::Verdict::Flip: return "";
    case ref::Verdict::WrongMissed: return "missed a surface the reference hits robustly: " + Describe(h, ref, i);
    case ref::Verdict::WrongFarther: return "a robust nearer surface exists: " + Describe(h, ref, i);
    case ref::Verdict::WrongNotOnPrim: return "not an intersection of that primitive: " + Describe(h, ref, i);
  }
  return "?";
}

}  // namespace

std::string JudgeAnswer(const HardCase& c, const CaseReference& ref, std::size_t i, const HitRecord& h,
                        bool occlusion)
{
  const Scene& scene = *c.scene;
  const RayRecord& r = c.rays[i];
  if (std::string bad = WellFormed(scene, h, occlusion); !bad.empty()) return bad;
  const bool miss = h.prim == CR_NO_HIT;
  switch (c.expect) {
    case Expect::Reference: break;
    case Expect::Closed: {
      // Convex closed meshes: the ray crosses the surface once, at
      // x* = o + t* d (the reference's t*). The answer must name a triangle
      // that contains x* and (closest) report t* itself, both within delta.
      if (miss) return "leak: a miss from inside a closed mesh";
      const double tRef = ref.t[i];
      if (!std::isfinite(tRef)) return "the reference misses (generator error)";
      const glm::dvec3 o(r.org[0], r.org[1], r.org[2]), d(r.dir[0], r.dir[1], r.dir[2]);
      const double deltaRef = Delta(r, tRef);
      if (!(ref.tracer->DistanceToPrim(h.prim, o + tRef * d) <= deltaRef))
        return "names a triangle away from the first crossing: " + Describe(h, ref, i);
      if (occlusion) return "";
      if (!(std::fabs(double(h.t) - tRef) * glm::length(d) <= deltaRef))
        return "t is not the first crossing's: " + Describe(h, ref, i);
      return "";
    }
    case Expect::Target: {
      const std::uint32_t want = c.target[i];
      if (want == kAnyPrim) break;
      if (want == CR_NO_HIT) return miss ? "" : "a hit where the ray passes the surface: " + Describe(h, ref, i);
      if (miss) return "a miss: " + Describe(h, ref, i);
      if (occlusion) break;
      if (h.prim != want) return fmt::format("id {}, expected {}: {}", h.prim, want, Describe(h, ref, i));
      if (c.relTolT > 0.0 && !(std::fabs(double(h.t) - ref.t[i]) <= c.relTolT * ref.t[i]))
        return fmt::format("t off by {:.3g} relative: {}", std::fabs(double(h.t) - ref.t[i]) / ref.t[i],
                           Describe(h, ref, i));
      break;
    }
    case Expect::Backstopped:
      if (miss) return "a miss (every ray ends on a backstop)";
      break;
    case Expect::NotSelf:
      if (!miss && h.prim == c.target[i]) {
        if (occlusion ? !(c.ownT[i] <= double(r.tmax)) : !(double(h.t) >= 0.5 * c.ownT[i]))
          return fmt::format("self-intersection: reports its own surface at t = {} ({})", h.t, Describe(h, ref, i));
      }
      break;
  }
  return ReferenceVerdict(c, ref, i, h, occlusion);
}

namespace {

// Judges every answer of one query; counts wrong rays into `wrongRay`.
void JudgeAll(const HardCase& c, const CaseReference& ref, const std::vector<HitRecord>& hits, bool occlusion,
              std::vector<std::uint8_t>& wrongRay, std::vector<std::string>& firstWrong)
{
  std::mutex mutex;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, c.rays.size(), 256), [&](const tbb::blocked_range<std::size_t>& br) {
    for (std::size_t i = br.begin(); i != br.end(); ++i) {
      std::string why = JudgeAnswer(c, ref, i, hits[i], occlusion);
      if (why.empty()) continue;
      wrongRay[i] = 1;
      std::lock_guard<std::mutex> lock(mutex);
      if (firstWrong.size() < 4) {
        const RayRecord& r = c.rays[i];
        firstWrong.push_back(fmt::format("ray {} ({}) o ({}, {}, {}) d ({}, {}, {}): {}", i,
                                         occlusion ? "occlusion" : "closest", r.org[0], r.org[1], r.org[2], r.dir[0],
                                         r.dir[1], r.dir[2], why));
      }
    }
  });
}

}  // namespace

CaseRun RunCase(const HardCase& c, const CaseReference& ref, const TraceConfig& config)
{
  CaseRun run;
  if (config.backend == Backend::Reference && c.build != BuildExpect::Ok) {
    run.note = "not applicable: the reference builds no structure";
    return run;
  }
  const bool mustThrow = c.build == BuildExpect::ThrowsInput || c.build == BuildExpect::ThrowsRuntime;
  const long warningsBefore = WarningCount();
  std::unique_ptr<Tracer> tracer;
  try {
    tracer = CreateTracer(*c.scene, config);
  } catch (const InputError& e) {
    if (c.build == BuildExpect::ThrowsInput) {
      run.note = fmt::format("InputError as expected: {}", e.what());
    } else {
      run.rays = 1;
      run.wrong = 1;
      run.note = fmt::format("unexpected InputError: {}", e.what());
    }
    return run;
  } catch (const RuntimeError& e) {
    if (c.build == BuildExpect::ThrowsRuntime) {
      run.note = fmt::format("RuntimeError as expected: {}", e.what());
    } else {
      run.rays = 1;
      run.wrong = 1;
      run.note = fmt::format("unexpected RuntimeError: {}", e.what());
    }
    return run;
  }
  if (mustThrow) {
    run.rays = 1;
    run.wrong = 1;
    run.note = c.build == BuildExpect::ThrowsInput ? "built without the expected InputError"
                                                   : "built without the expected RuntimeError";
    return run;
  }
  const long buildWarnings = WarningCount() - warningsBefore;

  run.rays = c.rays.size();
  std::vector<std::uint8_t> wrongRay(c.rays.size(), 0);
  std::vector<HitRecord> hits;
  for (int q = 0; q < 2; ++q) {
    const bool occlusion = q == 1;
    if (occlusion ? !c.occlusion : !c.closest) continue;
    tracer->Trace(c.rays, hits, occlusion, nullptr);
    if (hits.size() != c.rays.size()) {
      run.wrong = run.rays;
      run.note = fmt::format("{} answers for {} rays", hits.size(), c.rays.size());
      return run;
    }
    JudgeAll(c, ref, hits, occlusion, wrongRay, run.firstWrong);
  }
  for (std::uint8_t w : wrongRay) run.wrong += w;
  if (c.build == BuildExpect::Warns) {
    if (buildWarnings > 0) {
      run.note = "clamped with a warning";
    } else {
      run.wrong = std::max<std::uint64_t>(run.wrong, 1);
      run.note = "built without the expected warning";
    }
  }
  if (c.expectGeneratorWarnings > 0 && c.generatorWarnings < c.expectGeneratorWarnings) {
    run.wrong = std::max<std::uint64_t>(run.wrong, 1);
    run.note = fmt::format("the scene gave {} warnings, expected at least {}", c.generatorWarnings,
                           c.expectGeneratorWarnings);
  }
  return run;
}

}  // namespace cr::hard
