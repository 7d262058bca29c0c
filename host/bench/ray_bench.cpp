#include "host/bench/ray_bench.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <string_view>

#include <fmt/format.h>
#include <tbb/info.h>

#include "host/bench/machine_info.h"
#include "host/bench/ray_cache.h"
#include "host/core/error.h"
#include "host/reference/check.h"
#include "host/reference/reference.h"

namespace cr::bench {

namespace {

double MsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Identical hit sets get identical verdicts: robust configurations usually
// answer bit for bit alike (kernels/ray.h Hit_Closer), so the reference check
// runs once per distinct answer set of a ray set.
std::size_t HashHits(const std::vector<HitRecord>& hits)
{
  return std::hash<std::string_view>{}(
      std::string_view(reinterpret_cast<const char*>(hits.data()), hits.size() * sizeof(HitRecord)));
}

ErrorSummary Summarise(const ref::CheckResult& c)
{
  return ErrorSummary{c.agree, c.ties, c.flips, c.wrong, c.maxRelTErr, c.meanRelTErr};
}

}  // namespace

namespace {

// One timed Trace() of a prepared tracer: its wall time and, where the backend
// reports one, its kernels' time.
void TimeOnce(Tracer& tracer, const std::vector<RayRecord>& rays, const std::vector<float>& times, bool occlusion,
              std::vector<HitRecord>& scratch, std::vector<double>& ms, std::vector<double>& kernelMs)
{
  const auto t0 = std::chrono::steady_clock::now();
  tracer.Trace(rays, times, scratch, occlusion, nullptr);
  ms.push_back(MsSince(t0));
  if (tracer.LastKernelMs() >= 0.0) kernelMs.push_back(tracer.LastKernelMs());
}

Timing TimingOf(std::vector<double> ms, std::vector<double> kernelMs)
{
  const auto median = [](std::vector<double>& v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  Timing t;
  t.repeat = int(ms.size());
  if (!ms.empty()) {
    t.medianMs = median(ms);
    t.minMs = ms.front();
    t.maxMs = ms.back();
  }
  if (!kernelMs.empty() && kernelMs.size() == ms.size()) {
    t.kernelMedianMs = median(kernelMs);
    t.kernelMinMs = kernelMs.front();
    t.kernelMaxMs = kernelMs.back();
  }
  return t;
}

// A row whose timed runs wait for the scene's rounds (interleaved timing).
struct PendingRow {
  std::size_t row;  // index in the rows
  Tracer* tracer;
  const RaySet* set;
  bool occlusion;
  std::vector<double> ms, kernelMs;
  std::string variant;  // what the tracer ran on this row's last timed run
  bool failed = false;
};

}  // namespace

Timing TimeTrace(Tracer& tracer, const std::vector<RayRecord>& rays, const std::vector<float>& times, bool occlusion,
                 int repeat, std::vector<HitRecord>& hits)
{
  tracer.Prepare(occlusion);
  tracer.Trace(rays, times, hits, occlusion, nullptr);  // warm-up: caches, lazy device work; its answers are checked
  std::vector<double> ms, kernelMs;
  std::vector<HitRecord> scratch;
  for (int r = 0; r < repeat; ++r) TimeOnce(tracer, rays, times, occlusion, scratch, ms, kernelMs);
  return TimingOf(std::move(ms), std::move(kernelMs));
}

// The settings of the bench's SDF axis (BenchOptions::sdfEps, sdfRelax,
// sdfSteps) for a scene: one unsuffixed "as written" when the scene has no
// blocks or the axis is not asked for.
struct SdfSetting {
  std::string suffix;  // "@eps=E,w=W,steps=N", or empty: the scene as written
  double eps = 0.0, relax = 0.0;
  long steps = 0;
};
std::vector<SdfSetting> SdfSettings(const BenchOptions& o, const Scene& scene)
{
  if (scene.sdfs.empty() || (o.sdfEps.empty() && o.sdfRelax.empty() && o.sdfSteps.empty())) return {SdfSetting{}};
  const Sdf& first = scene.sdfs.front();
  const std::vector<double> eps = o.sdfEps.empty() ? std::vector<double>{first.eps} : o.sdfEps;
  const std::vector<double> relax = o.sdfRelax.empty() ? std::vector<double>{first.relax} : o.sdfRelax;
  const std::vector<long> steps = o.sdfSteps.empty() ? std::vector<long>{long(first.steps)} : o.sdfSteps;
  std::vector<SdfSetting> out;
  for (double e : eps)
    for (double w : relax)
      for (long n : steps) out.push_back(SdfSetting{fmt::format("@eps={},w={},steps={}", e, w, n), e, w, n});
  return out;
}

std::vector<Row> RunRayBench(const BenchOptions& o, const std::vector<SceneRef>& scenes, const std::vector<Combo>& combos,
                             const RowCallback& onRow, const NoteCallback& onNote)
{
  std::vector<Row> rows;
  std::size_t total = scenes.size() * combos.size() * o.kinds.size();
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  for (const SceneRef& sref : scenes) {
    Scene scene = LoadBenchScene(sref);
    const std::vector<SdfSetting> settings = SdfSettings(o, scene);
    total += (settings.size() - 1) * combos.size() * o.kinds.size();
    // The ray sets come from the scene as written; its SDF settings share them.
    std::unique_ptr<ref::ReferenceTracer> reference = std::make_unique<ref::ReferenceTracer>(scene);
    std::vector<RaySet> sets;
    for (RayKind k : o.kinds) sets.push_back(GetRaySet(o.outDir, sref, scene, *reference, RaySetSpec{k, o.rays, o.seed}));
    for (const SdfSetting& setting : settings) {
    if (!setting.suffix.empty()) {
      for (Sdf& b : scene.sdfs) {
        b.eps = float(setting.eps);
        b.relax = float(setting.relax);
        b.steps = std::uint32_t(setting.steps);
      }
      reference = std::make_unique<ref::ReferenceTracer>(scene);
    }
    const std::string suffix = setting.suffix;
    std::map<std::pair<std::size_t, std::size_t>, ErrorSummary> checked;  // (kind index, hits hash)
    // Interleaved timing: every configuration is built, warmed up and checked
    // first, its tracer kept; then `repeat` rounds each time every row once.
    const bool interleave = o.interleave && o.repeat > 1 && scene.NumUnified() <= o.interleaveMaxPieces;
    std::vector<std::unique_ptr<Tracer>> held;
    std::vector<PendingRow> pending;
    const std::size_t firstRow = rows.size();
    const std::uint64_t sceneRss = interleave ? CurrentRssBytes() : 0;

    for (const Combo& combo : combos) {
      Row proto;
      proto.scene = sref.name + suffix;
      proto.scenePath = sref.shown;
      proto.prims = scene.NumPrims();
      proto.pieces = scene.NumUnified();
      proto.combo = combo;
      proto.threads = threads;
      TraceConfig cfg;
      cfg.backend = combo.backend;
      cfg.accel = combo.accel;
      cfg.precision = combo.precision;
      cfg.variant = combo.variant;
      cfg.params = o.params;
      cfg.threads = o.threads;
      if (combo.backend == Backend::OpenCL) cfg.device = o.device;
      std::unique_ptr<Tracer> tracer, statsTracer;
      std::string skip;
      const bool rssKnown = ResetPeakRss();
      // What the earlier configurations' tracers hold (interleaved timing):
      // not this row's.
      const std::uint64_t rssNow = interleave ? CurrentRssBytes() : 0;
      const std::uint64_t heldRss = rssNow - std::min(rssNow, sceneRss);
      try {
        tracer = CreateTracer(scene, cfg);
        proto.structure = tracer->Info();
        proto.device = tracer->DeviceName();
      } catch (const InputError& e) {
        skip = fmt::format("skipped: {}", e.what());
      } catch (const RuntimeError& e) {
        skip = fmt::format("skipped: {}", e.what());
      }
      const bool wantStats = o.stats && tracer && combo.backend != Backend::Embree &&
                             combo.backend != Backend::Reference && proto.pieces <= o.statsMaxPieces;
      for (std::size_t ki = 0; ki < o.kinds.size(); ++ki) {
        Row row = proto;
        row.kind = o.kinds[ki];
        const RaySet& set = sets[ki];
        row.rays = set.rays.size();
        const bool occlusion = IsOcclusionKind(row.kind);
        if (!skip.empty()) {
          row.note = skip;
        } else if (set.rays.empty()) {
          // Why, as the ray generator said (no point light for shadow rays,
          // no primary hits for secondary rays).
          row.note = fmt::format("skipped: the ray set is empty ({})",
                                 set.why.empty() ? "no primary hits for secondary rays" : set.why);
        } else {
          try {
            std::vector<HitRecord> hits;
            // Interleaved: the warm-up only here, the timed runs in the rounds.
            row.timing = TimeTrace(*tracer, set.rays, set.times, occlusion, interleave ? 0 : o.repeat, hits);
            if (interleave) pending.push_back(PendingRow{rows.size(), tracer.get(), &set, occlusion, {}, {}, {}});
            row.variantRan = tracer->VariantName();
            for (const auto& h : hits) row.hits += h.prim != CR_NO_HIT;
            if (wantStats) {
              if (!statsTracer) {
                TraceConfig sc = cfg;
                sc.stats = true;
                statsTracer = CreateTracer(scene, sc);
              }
              TraceStatsSum sum;
              std::vector<HitRecord> statsHits;
              statsTracer->Prepare(occlusion);
              statsTracer->Trace(set.rays, set.times, statsHits, occlusion, &sum);
              const double n = double(set.rays.size());
              row.perRay = PerRay{double(sum.nIT) / n, double(sum.nTS) / n, double(sum.nLeaves) / n,
                                  double(sum.nEmptyLeaves) / n};
            }
            const auto key = std::make_pair(ki, HashHits(hits));
            auto it = checked.find(key);
            if (it == checked.end())
              it = checked.emplace(key, Summarise(ref::CheckHits(*reference, set.rays, hits, occlusion, set.times))).first;
            row.error = it->second;
          } catch (const InputError& e) {
            row.note = fmt::format("skipped: {}", e.what());
          } catch (const RuntimeError& e) {
            row.note = fmt::format("failed: {}", e.what());
          }
        }
        if (rssKnown) row.peakRssBytes = PeakRssBytes() - std::min(PeakRssBytes(), heldRss);
        rows.push_back(row);
        if (onRow && !interleave) onRow(rows.back(), rows.size(), total);
      }
      if (interleave && tracer) held.push_back(std::move(tracer));
    }
    if (interleave) {
      if (onNote)
        onNote(fmt::format("{}: {} rows built and checked; timing them in {} interleaved rounds", sref.name + suffix,
                           pending.size(), o.repeat));
      std::vector<HitRecord> scratch;
      const auto fail = [&](PendingRow& p, const char* what) {
        rows[p.row].note = fmt::format("failed: {}", what);
        p.failed = true;
      };
      for (int r = 0; r < o.repeat; ++r)
        for (PendingRow& p : pending) {
          if (p.failed) continue;
          try {
            // An untimed run first: the other rows have since filled the
            // caches with their structures, and a back-to-back run finds
            // its own there (the rounds measure drift, not a cold cache).
            p.tracer->Prepare(p.occlusion);
            p.tracer->Trace(p.set->rays, p.set->times, scratch, p.occlusion, nullptr);
            TimeOnce(*p.tracer, p.set->rays, p.set->times, p.occlusion, scratch, p.ms, p.kernelMs);
            p.variant = p.tracer->VariantName();
          } catch (const InputError& e) {
            fail(p, e.what());
          } catch (const RuntimeError& e) {
            fail(p, e.what());
          }
        }
      for (PendingRow& p : pending)
        if (!p.failed) {
          rows[p.row].timing = TimingOf(std::move(p.ms), std::move(p.kernelMs));
          rows[p.row].variantRan = p.variant;
          rows[p.row].interleaved = true;
        }
      held.clear();
      if (onRow)
        for (std::size_t i = firstRow; i < rows.size(); ++i) onRow(rows[i], i + 1, total);
    }
    }
  }
  return rows;
}

}  // namespace cr::bench
