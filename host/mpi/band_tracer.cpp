#include "host/mpi/band_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <type_traits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/error.h"
#include "host/mpi/mpi.h"

namespace cr {

namespace {

constexpr double kPi = 3.14159265358979323846;
// A box is padded by this share of its distance from the eye before its
// wedges are found: far more than the error of a float hit point (so a hit
// in wedge r always lies on a primitive rank r holds), and it costs only a
// few primitives held twice.
constexpr double kPad = 1e-3;

double Cross(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

double Ms(std::chrono::steady_clock::time_point a)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
}

// A ray on its way through the ring of wedges (a message between ranks).
struct Travel {
  RayRecord ray;
  HitRecord best;        // nearest hit so far (closest) / blocker (occlusion)
  double tPrev;          // where the ray entered the current wedge
  float time;            // shutter time
  std::uint32_t origin;  // the rank whose render cast it, and its index there
  std::uint32_t index;
  std::uint32_t start;   // first wedge of its run
  std::uint16_t hop, hops;
  std::uint8_t occlusion;
  std::int8_t step;      // -1: towards rank 0 (elevation rising), +1: away
};
static_assert(std::is_trivially_copyable_v<Travel> && sizeof(Travel) == 80);

struct Answer {
  std::uint32_t index;
  HitRecord hit;
};
static_assert(std::is_trivially_copyable_v<Answer>);

template <class T>
void Append(std::vector<char>& out, const T* v, std::size_t n)
{
  const std::size_t at = out.size();
  out.resize(at + n * sizeof(T));
  if (n) std::memcpy(out.data() + at, v, n * sizeof(T));
}

// The scene with only the pieces of `keep` (by unified index); toGlobal
// maps its unified indices back to the scene's. Statement data (ids,
// materials, motion) is kept whole; PrimInfo's piece ranges are not
// meaningful in it (no tracer reads them).
Scene SubScene(const Scene& scene, const std::vector<char>& keep, std::vector<std::uint32_t>& toGlobal)
{
  Scene sub = scene;
  const PrimRanges r = scene.Ranges();
  toGlobal.clear();
#define CR_SUB_(T, U, a)                                                                   \
  {                                                                                        \
    auto& v = sub.a;                                                                       \
    auto& ids = sub.pieceIds[CR_PRIM_##U];                                                 \
    const bool normals = CR_PRIM_##U == CR_PRIM_TRIANGLE && !sub.triNormals.empty();        \
    std::size_t n = 0;                                                                     \
    for (std::size_t i = 0; i < v.size(); ++i) {                                           \
      const std::uint32_t g = r.begin[CR_PRIM_##U] + std::uint32_t(i);                     \
      if (!keep[g]) continue;                                                              \
      v[n] = v[i];                                                                         \
      ids[n] = ids[i];                                                                     \
      if (normals) sub.triNormals[n] = sub.triNormals[i];                                  \
      toGlobal.push_back(g);                                                               \
      ++n;                                                                                 \
    }                                                                                      \
    v.resize(n);                                                                           \
    v.shrink_to_fit();                                                                     \
    ids.resize(n);                                                                         \
    if (normals) sub.triNormals.resize(n);                                                 \
  }
  CR_PRIM_TYPES(CR_SUB_)
#undef CR_SUB_
  return sub;
}

}  // namespace

void to_json(nlohmann::json& j, const BandStats& s)
{
  j = nlohmann::json{{"own_rays", s.ownRays},           {"own_shadow_rays", s.ownShadowRays},
                     {"left_rays", s.leftRays},         {"left_shadow_rays", s.leftShadowRays},
                     {"forwarded", s.forwarded},        {"answered", s.answered},
                     {"received", s.received},          {"rounds", s.rounds},
                     {"local_pieces", s.localPieces},   {"total_pieces", s.totalPieces},
                     {"structure_bytes", s.structureBytes}, {"trace_ms", s.traceMs},
                     {"exchange_ms", s.exchangeMs},     {"serve_ms", s.serveMs}};
}

BandWedges BandWedges::ForRows(const CameraFrame& frame, int n)
{
  BandWedges w;
  w.eye = frame.eye;
  w.forward = frame.forward;
  w.up = frame.up;
  w.upper.assign(std::size_t(n) + 1, 0.0);
  w.upper[0] = kPi;
  w.upper[std::size_t(n)] = -kPi;
  for (int r = 1; r < n; ++r) {
    const int y = int(std::int64_t(frame.height) * r / n);
    const RayRecord ray = PrimaryRay(frame, 0.5 * (frame.width - 1), y - 0.5);
    const glm::dvec3 d(ray.dir[0], ray.dir[1], ray.dir[2]);
    // Never rising: an empty band (more ranks than rows) is an empty wedge.
    w.upper[std::size_t(r)] = std::min(w.upper[std::size_t(r) - 1], std::atan2(glm::dot(d, w.up), glm::dot(d, w.forward)));
  }
  for (double a : w.upper) w.unit.emplace_back(std::cos(a), std::sin(a));
  return w;
}

glm::dvec2 BandWedges::Project(const glm::dvec3& p) const
{
  const glm::dvec3 v = p - eye;
  return {glm::dot(v, forward), glm::dot(v, up)};
}

int BandWedges::WedgeOf(double angle) const
{
  const int n = Count();
  for (int r = 0; r < n - 1; ++r)
    if (angle > upper[std::size_t(r) + 1]) return r;
  return n - 1;
}

int BandWedges::WedgeOfPoint(const glm::dvec2& q) const
{
  const int n = Count();
  if (n == 1) return 0;
  // Behind the plane of the eye: beyond the inner boundaries.
  if (!(q.x > 0.0)) return q.y > 0.0 || (q.y == 0.0 && !std::signbit(q.y)) ? 0 : n - 1;
  // In front: the first r whose lower boundary the point lies above
  // (angle > upper[r + 1] when u x q > 0), boundaries falling with r.
  int lo = 0, hi = n - 1;  // the answer is in [lo, hi]
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (Cross(unit[std::size_t(mid) + 1], q) > 0.0) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

std::vector<bool> BandWedges::WedgesOfBox(const Bounds& box) const
{
  const int n = Count();
  std::vector<bool> in(std::size_t(n), true);
  const glm::dvec3 lo(box.lo), hi(box.hi);
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a])) return in;
  double dist = 0.0;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
    dist = std::max(dist, glm::length(p - eye));
  }
  const double pad = kPad * dist;
  double angle[8];
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p(c & 1 ? hi.x + pad : lo.x - pad, c & 2 ? hi.y + pad : lo.y - pad, c & 4 ? hi.z + pad : lo.z - pad);
    const glm::dvec2 q = Project(p);
    if (q.x == 0.0 && q.y == 0.0) return in;
    angle[c] = std::atan2(q.y, q.x);
  }
  std::sort(angle, angle + 8);
  // The largest gap between the corners' angles: under half a turn, the
  // box surrounds the axis and meets every wedge.
  int gapAt = 7;
  double gap = angle[0] + 2.0 * kPi - angle[7];
  for (int c = 0; c < 7; ++c)
    if (angle[c + 1] - angle[c] > gap) gap = angle[c + 1] - angle[c], gapAt = c;
  if (gap <= kPi) return in;
  // The box's arc: from the corner after the gap, counter-clockwise.
  const double from = angle[(gapAt + 1) % 8];
  const double to = from + (2.0 * kPi - gap);
  for (int r = 0; r < n; ++r) {
    const double wlo = upper[std::size_t(r) + 1], whi = upper[std::size_t(r)];
    const bool meets = (from <= whi && to >= wlo) || (from <= whi + 2.0 * kPi && to >= wlo + 2.0 * kPi);
    in[std::size_t(r)] = meets;
  }
  return in;
}

BandWedges::Run BandWedges::RunOf(const RayRecord& ray) const
{
  const int n = Count();
  const glm::dvec3 o(ray.org[0], ray.org[1], ray.org[2]);
  const glm::dvec3 d(ray.dir[0], ray.dir[1], ray.dir[2]);
  const glm::dvec2 a = Project(o), b(glm::dot(d, forward), glm::dot(d, up));
  auto wedgeAt = [&](double t) {
    glm::dvec2 q = std::isinf(t) ? b : t != 0.0 ? a + t * b : a;
    // On the axis itself (a ray from the eye): the direction it leaves in.
    if (q.x == 0.0 && q.y == 0.0) q = b;
    if (q.x == 0.0 && q.y == 0.0) q = a;
    return WedgeOfPoint(q);
  };
  const int s = wedgeAt(double(ray.tmin));
  const int e = wedgeAt(double(ray.tmax));
  Run run;
  // Seen along the axis the ray turns counter-clockwise (elevation rising,
  // towards wedge 0) when a x b > 0; through the axis itself either way
  // reaches its last wedge (the wedges between meet it only on the axis,
  // where every primitive there is in every wedge).
  run.step = Cross(a, b) > 1e-12 * glm::length(a) * glm::length(b) ? -1 : 1;
  run.start = s;
  run.hops = ((e - s) * run.step % n + n) % n;
  return run;
}

double BandWedges::Exit(const RayRecord& ray, const Run& run, int k, double tPrev) const
{
  if (k >= run.hops) return double(ray.tmax);
  const int w = At(run, k);
  const glm::dvec2 u = run.step < 0 ? unit[std::size_t(w)] : unit[std::size_t(w) + 1];
  const glm::dvec3 o(ray.org[0], ray.org[1], ray.org[2]);
  const glm::dvec3 d(ray.dir[0], ray.dir[1], ray.dir[2]);
  const glm::dvec2 a = Project(o), b(glm::dot(d, forward), glm::dot(d, up));
  // Where the ray meets the plane of the boundary (its half on beta's side:
  // the run says the ray turns towards it).
  const double den = Cross(u, b);
  double x = den != 0.0 ? -Cross(u, a) / den : tPrev;
  if (!(x >= tPrev)) x = tPrev;
  return std::min(x, double(ray.tmax));
}

struct BandTracer::Impl {
  const Scene& scene;
  TraceConfig config;
  BandWedges wedges;
  int rank = 0, ranks = 1;
  Scene sub;                       // this wedge's pieces (tracers may keep a reference to their scene)
  std::unique_ptr<Tracer> local;  // null when no piece lies in this wedge
  std::vector<std::uint32_t> toGlobal;
  std::vector<Travel> queue;                // rays to trace here in the next round
  std::vector<std::vector<char>> outbox, inbox;  // per rank: rays passed on, then answers
  std::vector<std::vector<Travel>> fwdOut;  // per rank
  std::vector<std::vector<Answer>> ansOut;
  std::vector<HitRecord>* hits = nullptr;   // the answers of this rank's Trace call
  std::size_t pending = 0;
  bool finished = false;
  std::uint64_t globalWork = 0;  // after a round: rays queued anywhere + ranks not finished
  BandStats* stats = nullptr;
  // Scratch of a round.
  std::vector<RayRecord> rays;
  std::vector<float> times;
  std::vector<HitRecord> got;
  std::vector<std::size_t> which;

  Impl(const Scene& s, const TraceConfig& c, const BandWedges& w) : scene(s), config(c), wedges(w) {}

  static BandWedges::Run RunOf(const Travel& t) { return {int(t.start), int(t.step), int(t.hops)}; }
  int WedgeAt(const Travel& t, int hop) const { return wedges.At(RunOf(t), hop); }
  void Plan(Travel& t) const
  {
    const BandWedges::Run run = wedges.RunOf(t.ray);
    t.start = std::uint32_t(run.start);
    t.step = std::int8_t(run.step);
    t.hops = std::uint16_t(run.hops);
    t.hop = 0;
    t.tPrev = double(t.ray.tmin);
  }
  double Exit(const Travel& t) const { return wedges.Exit(t.ray, RunOf(t), t.hop, t.tPrev); }

  void Send(const Travel& t)
  {
    const int w = WedgeAt(t, t.hop);
    fwdOut[std::size_t(w)].push_back(t);
    ++stats->forwarded;
  }

  void Answered(const Travel& t)
  {
    if (int(t.origin) == rank) {
      (*hits)[t.index] = t.best;
      --pending;
    } else {
      ansOut[t.origin].push_back(Answer{t.index, t.best});
      ++stats->answered;
    }
  }

  // Traces the queue against this rank's structure, then passes on or
  // answers each ray; exchanges with every rank; counts the work left.
  void Round()
  {
    ++stats->rounds;
    const auto t0 = std::chrono::steady_clock::now();
    for (int occl = 0; occl < 2; ++occl) {
      which.clear();
      for (std::size_t i = 0; i < queue.size(); ++i)
        if (queue[i].occlusion == occl) which.push_back(i);
      if (which.empty()) continue;
      rays.resize(which.size());
      times.clear();
      if (scene.hasMotion) times.resize(which.size());
      for (std::size_t k = 0; k < which.size(); ++k) {
        const Travel& t = queue[which[k]];
        rays[k] = t.ray;
        // Nothing beyond the nearest hit found so far can be nearer.
        if (!occl && t.best.prim != CR_NO_HIT) rays[k].tmax = std::min(rays[k].tmax, t.best.t);
        if (scene.hasMotion) times[k] = t.time;
      }
      got.assign(which.size(), HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f});
      if (local) local->Trace(rays, times, got, occl != 0, nullptr);
      for (std::size_t k = 0; k < which.size(); ++k) {
        Travel& t = queue[which[k]];
        HitRecord h = got[k];
        if (h.prim != CR_NO_HIT && config.unifiedHits) h.prim = toGlobal[h.prim];
        if (h.prim != CR_NO_HIT && (t.best.prim == CR_NO_HIT || (!occl && h.t < t.best.t))) t.best = h;
        const double exit = t.hop >= t.hops ? double(t.ray.tmax) : Exit(t);
        const bool done = occl ? t.best.prim != CR_NO_HIT || t.hop >= t.hops
                               : t.hop >= t.hops || (t.best.prim != CR_NO_HIT && double(t.best.t) <= exit);
        if (done) {
          Answered(t);
        } else {
          // A ray of this rank's that leaves its band (counted once: when it
          // starts in another band, Trace counted it).
          if (int(t.origin) == rank && t.hop == 0 && int(t.start) == rank) ++(occl ? stats->leftShadowRays : stats->leftRays);
          t.tPrev = exit;
          ++t.hop;
          Send(t);
        }
      }
    }
    queue.clear();
    stats->traceMs += Ms(t0);

    const auto t1 = std::chrono::steady_clock::now();
    for (int r = 0; r < ranks; ++r) {
      std::vector<char>& out = outbox[std::size_t(r)];
      out.clear();
      const std::uint32_t nf = std::uint32_t(fwdOut[std::size_t(r)].size()), na = std::uint32_t(ansOut[std::size_t(r)].size());
      if (nf + na == 0) continue;
      Append(out, &nf, 1);
      Append(out, &na, 1);
      Append(out, fwdOut[std::size_t(r)].data(), nf);
      Append(out, ansOut[std::size_t(r)].data(), na);
      fwdOut[std::size_t(r)].clear();
      ansOut[std::size_t(r)].clear();
    }
    mpi::Exchange(outbox, inbox);
    for (const std::vector<char>& msg : inbox) {
      if (msg.empty()) continue;
      std::uint32_t nf = 0, na = 0;
      std::memcpy(&nf, msg.data(), 4);
      std::memcpy(&na, msg.data() + 4, 4);
      if (msg.size() != 8 + std::size_t(nf) * sizeof(Travel) + std::size_t(na) * sizeof(Answer))
        throw RuntimeError(fmt::format("bands-data: a message of {} bytes does not hold {} rays and {} answers", msg.size(), nf, na));
      const char* p = msg.data() + 8;
      const std::size_t q0 = queue.size();
      queue.resize(q0 + nf);
      if (nf) std::memcpy(queue.data() + q0, p, std::size_t(nf) * sizeof(Travel));
      p += std::size_t(nf) * sizeof(Travel);
      for (std::size_t i = q0; i < queue.size(); ++i)
        if (int(queue[i].origin) != rank) ++stats->received;
      for (std::uint32_t i = 0; i < na; ++i, p += sizeof(Answer)) {
        Answer a;
        std::memcpy(&a, p, sizeof a);
        (*hits)[a.index] = a.hit;
        --pending;
      }
    }
    std::uint64_t work[1] = {std::uint64_t(queue.size()) + (finished ? 0u : 1u)};
    mpi::SumAll(work, 1);
    globalWork = work[0];
    stats->exchangeMs += Ms(t1);
  }
};

BandTracer::BandTracer(const Scene& scene, const TraceConfig& config, const BandWedges& wedges)
    : impl_(std::make_unique<Impl>(scene, config, wedges))
{
  Impl& m = *impl_;
  m.rank = mpi::Rank();
  m.ranks = mpi::Size();
  m.stats = &stats_;
  if (wedges.Count() != m.ranks)
    throw RuntimeError(fmt::format("bands-data: {} wedges for {} ranks", wedges.Count(), m.ranks));
  m.outbox.resize(std::size_t(m.ranks));
  m.fwdOut.resize(std::size_t(m.ranks));
  m.ansOut.resize(std::size_t(m.ranks));
  const std::uint32_t n = scene.NumUnified();
  std::vector<char> keep(n, 0);
  std::uint64_t kept = 0;
  for (std::uint32_t g = 0; g < n; ++g) {
    const std::vector<bool> in = wedges.WedgesOfBox(scene.UnifiedBounds(g));
    keep[g] = in[std::size_t(m.rank)] ? 1 : 0;
    kept += keep[g];
  }
  stats_.totalPieces = n;
  stats_.localPieces = kept;
  backend_ = config.backend;
  if (kept > 0) {
    m.sub = SubScene(scene, keep, m.toGlobal);
    m.local = CreateTracer(m.sub, config);
    info_ = m.local->Info();
    stats_.structureBytes = info_.bytes;
  }
}

BandTracer::~BandTracer() = default;

void BandTracer::TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
                       bool occlusion, TraceStatsSum* stats)
{
  (void)stats;
  Impl& m = *impl_;
  hits.assign(rays.size(), HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f});
  if (rays.empty()) return;
  m.hits = &hits;
  m.pending = rays.size();
  (occlusion ? stats_.ownShadowRays : stats_.ownRays) += rays.size();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    Travel t{};
    t.ray = rays[i];
    t.best = HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
    t.time = times.empty() ? 0.0f : times[i];
    t.origin = std::uint32_t(m.rank);
    t.index = std::uint32_t(i);
    t.occlusion = occlusion ? 1 : 0;
    m.Plan(t);
    if (int(t.start) == m.rank) {
      m.queue.push_back(t);
    } else {
      ++(occlusion ? stats_.leftShadowRays : stats_.leftRays);
      m.Send(t);
    }
  }
  while (m.pending > 0) m.Round();
  m.hits = nullptr;
}

void BandTracer::Finish()
{
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  m.finished = true;
  std::vector<HitRecord> none;
  m.hits = &none;
  do m.Round();
  while (m.globalWork != 0);
  m.hits = nullptr;
  stats_.serveMs += Ms(t0);
}

std::string BandTracer::DeviceName() const { return impl_->local ? impl_->local->DeviceName() : std::string("none"); }
std::string BandTracer::VariantName() const { return impl_->local ? impl_->local->VariantName() : std::string(); }
Backend BandTracer::ActiveBackend() const { return impl_->local ? impl_->local->ActiveBackend() : backend_; }
std::string BandTracer::FallbackReason() const { return impl_->local ? impl_->local->FallbackReason() : std::string(); }

}  // namespace cr
