#include "host/reference/check.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "host/prims/prim_host.h"

namespace cr::ref {

namespace {


// The tolerance of check.h at t: the ray's magnitudes up to t, nothing of
// the scene or the primitive.
// A ray shifted into a moving primitive's frame (ReferenceTracer::Framed)
// counts its origin as |o'| + 2 |shift|: the world origin's magnitude is at
// most |o'| + |shift|, and a float tracer rounds o - shift at the scale
// |o| + |shift|.
double Delta(const DRay& r, double t) { return CheckDelta(MaxAbs(r.o) + 2.0 * r.shift, MaxAbs(r.d), t); }

// The slack of primitive `prim` (HitSlack, host/prims/prim_host.h): 0 but
// for an SDF block, whose hits lie within its eps of the surface by
// definition. Added to the tolerance wherever a hit on `prim` is judged.
double Slack(const ReferenceTracer& tr, std::uint32_t prim)
{
  const Scene& scene = tr.GetScene();
  const PrimRanges ranges = scene.Ranges();
  if (Prim_Count(&ranges, CR_PRIM_SDF) == 0) return 0.0;
  std::vector<std::uint32_t> pieces;
  tr.PiecesOf(prim, pieces);
  double s = 0.0;
  for (std::uint32_t g : pieces)
    scene.Visit(ranges, g, [&](const auto& piece, std::uint32_t) { s = std::max(s, HitSlack(piece)); });
  return s;
}

// Does the ray meet primitive `prim` (any piece) in [tmin, tmax]?
bool MeetsPrim(const ReferenceTracer& tr, std::uint32_t prim, const DRay& r, std::vector<std::uint32_t>& pieces)
{
  tr.PiecesOf(prim, pieces);
  for (std::uint32_t g : pieces) {
    double t[2];
    if (tr.PrimRoots(prim, g, r, t) > 0) return true;
  }
  return false;
}

void Perpendiculars(const glm::dvec3& d, glm::dvec3& e1, glm::dvec3& e2)
{
  glm::dvec3 n = glm::normalize(d);
  glm::dvec3 a = std::fabs(n.x) < 0.6 ? glm::dvec3(1, 0, 0) : (std::fabs(n.y) < 0.6 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1));
  e1 = glm::normalize(glm::cross(n, a));
  e2 = glm::cross(n, e1);
}

// Marginal, PossiblyMeets and NearRay take the ray in the primitive's frame
// (ReferenceTracer::Framed: time 0, the primitive at rest), so that the
// rays they derive from it need no time.

// A hit at t on primitive `prim` is marginal when it lies within delta of the
// ray's ends or when some ray shifted sideways by delta misses the primitive.
bool Marginal(const ReferenceTracer& tr, std::uint32_t prim, const DRay& r, double t, double delta)
{
  double dl = glm::length(r.d);
  if ((t - r.tmin) * dl <= delta || (std::isfinite(r.tmax) && (r.tmax - t) * dl <= delta)) return true;
  glm::dvec3 e1, e2;
  Perpendiculars(r.d, e1, e2);
  std::vector<std::uint32_t> pieces;
  for (int k = 0; k < 8; ++k) {
    double a = k * (3.14159265358979323846 / 4.0);
    DRay s = MakeRay(r.o + delta * (std::cos(a) * e1 + std::sin(a) * e2), r.d, r.tmin, r.tmax);
    if (!MeetsPrim(tr, prim, s, pieces)) return true;
  }
  return false;
}

// Could primitive `prim` be met by the ray, up to delta?
bool PossiblyMeets(const ReferenceTracer& tr, std::uint32_t prim, const DRay& r, double delta)
{
  std::vector<std::uint32_t> pieces;
  double dl = glm::length(r.d);
  DRay widened = MakeRay(r.o, r.d, std::max(0.0, r.tmin - delta / dl), r.tmax + delta / dl);
  if (MeetsPrim(tr, prim, widened, pieces)) return true;
  glm::dvec3 e1, e2;
  Perpendiculars(r.d, e1, e2);
  for (int k = 0; k < 8; ++k) {
    double a = k * (3.14159265358979323846 / 4.0);
    DRay s = MakeRay(r.o + delta * (std::cos(a) * e1 + std::sin(a) * e2), r.d, widened.tmin, widened.tmax);
    if (MeetsPrim(tr, prim, s, pieces)) return true;
  }
  return false;
}

// Does the ray come within delta(t) of primitive `prim` somewhere in
// [tmin - delta, tmax + delta]? The distance from a segment to a triangle
// is smallest where the segment crosses it (MeetsPrim), at an end, or at its
// closest approach to an edge; to a sphere at the closest approach to the
// centre; each type names its own candidates (RefNearTimes). This catches what the eight shifted rays of PossiblyMeets miss: a
// ray through a triangle's vertex where the triangle's angle is narrower
// than their 45-degree spacing.
bool NearRay(const ReferenceTracer& tr, std::uint32_t prim, const DRay& r)
{
  const Scene& scene = tr.GetScene();
  const PrimRanges ranges = scene.Ranges();
  const double dl = glm::length(r.d);
  const double primSlack = Slack(tr, prim);
  auto delta = [&](double t) { return Delta(r, t) + primSlack; };
  std::vector<std::uint32_t> pieces;
  tr.PiecesOf(prim, pieces);
  for (std::uint32_t g : pieces) {
    // A ball around the piece makes the ray a segment; the piece's own
    // closest approaches (RefNearTimes, host/prims/) are sampled on it.
    glm::dvec3 mid;
    double reach = 0.0;
    scene.Visit(ranges, g, [&](const auto& piece, std::uint32_t) { RefBall(piece, mid, reach); });
    const double tc = glm::dot(mid - r.o, r.d) / (dl * dl);
    const double slack = (reach + delta(tc + reach / dl) + 1e-300) / dl;
    const double t0 = std::max({0.0, r.tmin - delta(r.tmin) / dl, tc - slack});
    const double t1 = std::min(r.tmax + delta(r.tmax) / dl, tc + slack);
    if (!(t0 <= t1)) continue;
    std::vector<double> ts = {t0, t1};
    scene.Visit(ranges, g, [&](const auto& piece, std::uint32_t) { RefNearTimes(piece, r, t0, t1, ts); });
    for (double t : ts)
      if (tr.DistanceToPrim(prim, r.o + t * r.d) <= delta(t)) return true;
  }
  return false;
}

}  // namespace

Verdict Adjudicate(const ReferenceTracer& tr, const RayRecord& rec, const HitRecord& hit, bool occlusion, double* relErr,
                   std::vector<RefHit>& all)
{
  return Adjudicate(tr, rec, 0.0f, hit, occlusion, relErr, all);
}

Verdict Adjudicate(const ReferenceTracer& tr, const RayRecord& rec, float time, const HitRecord& hit, bool occlusion,
                   double* relErr, std::vector<RefHit>& all)
{
  const Scene& scene = tr.GetScene();
  DRay r = MakeRay(rec);
  r.time = time;
  // The ray in primitive p's frame (a moving primitive's rest frame), and
  // the tolerance there.
  auto framed = [&](std::uint32_t p) { return tr.Framed(p, r); };
  auto deltaOn = [&](std::uint32_t p, double t) { return Delta(framed(p), t) + Slack(tr, p); };
  const double dl = glm::length(r.d);
  *relErr = -1.0;
  const bool testHit = hit.prim != CR_NO_HIT;
  if (testHit && hit.prim >= scene.NumPrims()) return Verdict::WrongNotOnPrim;
  // A reported miss (or "free") where the reference hits: a flip, excused
  // only when every surface on the ray is marginal.
  auto missVerdict = [&]() {
    tr.AllHits(r, all);
    for (const RefHit& h : all)
      if (!Marginal(tr, tr.IdOfHit(h), framed(tr.IdOfHit(h)), h.t, deltaOn(tr.IdOfHit(h), h.t)))
        return Verdict::WrongMissed;
    return Verdict::Flip;
  };

  if (occlusion) {
    RefHit any = tr.IntersectP(r);
    if (testHit) {
      std::vector<std::uint32_t> pieces;
      if (MeetsPrim(tr, hit.prim, r, pieces)) return Verdict::Agree;
      // Scale delta by where the primitive is along the ray (NearRay scales
      // it point by point).
      double far = std::isfinite(r.tmax) ? r.tmax : (any.Found() ? any.t : 0.0);
      const bool near =
          PossiblyMeets(tr, hit.prim, framed(hit.prim), deltaOn(hit.prim, far)) || NearRay(tr, hit.prim, framed(hit.prim));
      if (!near) return Verdict::WrongNotOnPrim;
      // Occluded is the right answer when the reference finds an occluder
      // too (the named one is off by less than delta: a tie); when it finds
      // none, occluded against free is a flip.
      return any.Found() ? Verdict::Tie : Verdict::Flip;
    }
    if (!any.Found()) return Verdict::Agree;
    return missVerdict();
  }

  RefHit ref = tr.Intersect(r);
  if (!testHit) return ref.Found() ? missVerdict() : Verdict::Agree;
  const double t = hit.t;
  const double delta = deltaOn(hit.prim, t);
  if (ref.Found() && tr.IdOfHit(ref) == hit.prim && std::fabs(t - ref.t) * dl <= delta) {
    // Relative to t, or near t = 0 (a ray from a surface meeting it again)
    // to the smallest distance the ray resolves: the float rounding of its
    // origin along it (2^-24 |o|inf / |d|inf); a t of 2e-15 reported as 0
    // is not an error of 100%.
    const double dInf = MaxAbs(r.d);
    const double floor = dInf > 0.0 ? std::ldexp(MaxAbs(r.o) / dInf, -24) : 0.0;
    const double scale = std::max(ref.t, floor);
    *relErr = scale > 0.0 ? std::fabs(t - ref.t) / scale : std::fabs(t - ref.t);
    return Verdict::Agree;
  }
  // The reported point must be on the reported primitive and inside the ray.
  if (!(t >= r.tmin - delta / dl && (t <= r.tmax + delta / dl))) return Verdict::WrongNotOnPrim;
  const glm::dvec3 p = framed(hit.prim).o + t * r.d;
  if (!(tr.DistanceToPrim(hit.prim, p) <= delta)) return Verdict::WrongNotOnPrim;
  // A hit where the reference finds none: the ray passes within delta of
  // the reported surface, a flip.
  if (!ref.Found()) return Verdict::Flip;
  // Nothing robust may lie before it.
  tr.AllHits(r, all);
  for (const RefHit& h : all) {
    const std::uint32_t hp = tr.IdOfHit(h);
    const double deltaH = deltaOn(hp, h.t);
    if ((t - h.t) * dl <= std::max(delta, deltaH)) continue;
    if (!Marginal(tr, hp, framed(hp), h.t, deltaH)) return Verdict::WrongFarther;
  }
  return Verdict::Tie;
}

CheckResult CheckHits(const ReferenceTracer& tr, const std::vector<RayRecord>& rays, const std::vector<HitRecord>& hits,
                      bool occlusion, const std::vector<float>& times)
{
  CheckResult res;
  res.rays = rays.size();
  std::vector<std::uint8_t> verdict(rays.size());
  std::vector<double> err(rays.size(), -1.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256), [&](const tbb::blocked_range<std::size_t>& br) {
    std::vector<RefHit> scratch;
    for (std::size_t i = br.begin(); i != br.end(); ++i)
      verdict[i] = static_cast<std::uint8_t>(
          Adjudicate(tr, rays[i], times.empty() ? 0.0f : times[i], hits[i], occlusion, &err[i], scratch));
  });
  double sumErr = 0.0;
  std::uint64_t nErr = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    auto v = static_cast<Verdict>(verdict[i]);
    switch (v) {
      case Verdict::Agree: ++res.agree; break;
      case Verdict::Tie: ++res.ties; break;
      case Verdict::Flip: ++res.flips; break;
      case Verdict::WrongMissed: ++res.wrongMissed; break;
      case Verdict::WrongFarther: ++res.wrongFarther; break;
      case Verdict::WrongNotOnPrim: ++res.wrongNotOnPrim; break;
    }
    if (IsWrong(v)) {
      ++res.wrong;
      if (res.firstWrong.size() < 16) {
        res.firstWrong.push_back(i);
        res.firstWrongWhy.push_back(v == Verdict::WrongMissed    ? "missed a surface"
                                    : v == Verdict::WrongFarther ? "a nearer surface exists"
                                                                 : "not an intersection of that primitive");
      }
    }
    if (err[i] >= 0.0) {
      res.maxRelTErr = std::max(res.maxRelTErr, err[i]);
      sumErr += err[i];
      ++nErr;
    }
  }
  res.meanRelTErr = nErr ? sumErr / double(nErr) : 0.0;
  return res;
}

}  // namespace cr::ref
