// The hard-case suite over every structure x backend x precision mode, and
// its report. The cases and their rules are in bench/hard_cases.h.
#include "tests/hard/gen/hard.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "tests/hard/gen/hard_cases.h"
#include "host/core/error.h"

namespace cr {

namespace {

bool Selected(const std::string& name, const std::vector<std::string>& filter)
{
  if (filter.empty()) return true;
  for (const std::string& f : filter)
    if (name == f || name.rfind(f, 0) == 0) return true;
  return false;
}

// Why a backend x precision cannot run here (empty: it can): a tracer is
// created for a one-sphere scene, which checks the device and its fp64.
std::string Unavailable(Backend b, Precision p)
{
  static std::map<std::pair<Backend, Precision>, std::string> cache;
  auto key = std::make_pair(b, p);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  Scene probe;
  probe.materials.push_back(Material{});
  PrimInfo info;
  info.nPieces = 1;
  probe.prims.push_back(info);
  probe.AddPiece(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f}, 0);
  std::string why;
  try {
    TraceConfig cfg;
    cfg.backend = b;
    cfg.precision = p;
    (void)CreateTracer(probe, cfg);
  } catch (const std::exception& e) {
    why = e.what();
  }
  return cache[key] = why;
}

std::vector<Backend> DefaultBackends() { return {Backend::Scalar, Backend::Simd, Backend::OpenCL}; }

}  // namespace

std::vector<HardCaseResult> RunHardSuite(const HardOptions& options)
{
  const std::vector<Backend> backends = options.backends.empty() ? DefaultBackends() : options.backends;
  const std::vector<AccelKind> accels =
      options.accels.empty() ? std::vector<AccelKind>(std::begin(kAccelKinds), std::end(kAccelKinds)) : options.accels;
  const std::vector<Precision> precisions =
      options.precisions.empty() ? std::vector<Precision>{Precision::Fast, Precision::Robust, Precision::Fp64}
                                 : options.precisions;
  hard::GenOptions gen;
  gen.quick = options.quick;
  std::vector<HardCaseResult> results;
  auto emit = [&](HardCaseResult r) {
    if (options.onResult) options.onResult(r);
    results.push_back(std::move(r));
  };

  // A filter that names no case is a typo, not an empty success.
  for (const std::string& f : options.cases) {
    bool any = false;
    for (const hard::CaseSpec& spec : hard::CaseSpecs()) any = any || Selected(spec.name, {f});
    if (!any) {
      std::string names;
      for (const hard::CaseSpec& spec : hard::CaseSpecs()) names += (names.empty() ? "" : ", ") + spec.name;
      throw InputError(fmt::format("--case '{}' names no hard case (cases: {})", f, names));
    }
  }
  for (const hard::CaseSpec& spec : hard::CaseSpecs()) {
    if (!Selected(spec.name, options.cases)) continue;
    std::optional<hard::HardCase> shared;
    std::optional<hard::CaseReference> sharedRef;
    std::string sharedError;
    for (AccelKind accel : accels) {
      std::optional<hard::HardCase> own;
      std::optional<hard::CaseReference> ownRef;
      std::string error;
      auto& c = spec.perAccel ? own : shared;
      auto& ref = spec.perAccel ? ownRef : sharedRef;
      std::string& err = spec.perAccel ? error : sharedError;
      if (!c && err.empty()) {
        try {
          c = spec.make(accel, gen);
          ref = hard::ComputeReference(*c);
        } catch (const std::exception& e) {
          err = e.what();
          c.reset();
        }
      }
      if (c && !c->accels.empty() && std::find(c->accels.begin(), c->accels.end(), accel) == c->accels.end())
        continue;  // the case does not apply to this structure
      for (Backend b : backends)
        for (Precision p : precisions) {
          HardCaseResult r;
          r.caseName = spec.name;
          r.accel = accel;
          r.backend = b;
          r.precision = p;
          if (!err.empty()) {
            r.rays = r.wrong = 1;
            r.required = true;
            r.note = "generator failed: " + err;
            emit(r);
            continue;
          }
          r.required = p == Precision::Fp64 || p == Precision::Robust;
          if (const std::string why = Unavailable(b, p); !why.empty()) {
            r.skipped = true;
            r.required = false;
            r.note = "skipped: " + why;
            emit(r);
            continue;
          }
          TraceConfig cfg;
          cfg.backend = b;
          cfg.accel = accel;
          cfg.precision = p;
          cfg.params = c->params;
          OverrideAccelParams(cfg.params, options.params);
          if (b == Backend::Simd) cfg.variant = options.simdVariant;
          try {
            const hard::CaseRun run = hard::RunCase(*c, *ref, cfg);
            r.rays = run.rays;
            r.wrong = run.wrong;
            r.note = run.note;
            for (const std::string& w : run.firstWrong) r.note += (r.note.empty() ? "" : "; ") + w;
          } catch (const std::exception& e) {
            r.rays = std::max<std::uint64_t>(c->rays.size(), 1);
            r.wrong = r.rays;
            r.note = fmt::format("error: {}", e.what());
          }
          emit(r);
        }
    }
  }
  return results;
}

namespace {

using Column = std::tuple<AccelKind, Backend, Precision>;

std::string ColumnName(const Column& c)
{
  return fmt::format("{} {} {}", AccelKindName(std::get<0>(c)), BackendName(std::get<1>(c)), PrecisionName(std::get<2>(c)));
}

}  // namespace

std::string HardTableMarkdown(const std::vector<HardCaseResult>& results)
{
  std::vector<std::string> rows;
  std::vector<Column> columns;
  std::map<std::pair<std::string, Column>, const HardCaseResult*> cell;
  for (const HardCaseResult& r : results) {
    if (std::find(rows.begin(), rows.end(), r.caseName) == rows.end()) rows.push_back(r.caseName);
    const Column col{r.accel, r.backend, r.precision};
    if (std::find(columns.begin(), columns.end(), col) == columns.end()) columns.push_back(col);
    cell[{r.caseName, col}] = &r;
  }
  std::sort(columns.begin(), columns.end());
  // Columns where nothing ran (a backend or precision not available here)
  // are left out and named below the table.
  std::vector<Column> shown, hidden;
  for (const Column& c : columns) {
    bool ran = false;
    for (const std::string& row : rows)
      if (auto it = cell.find({row, c}); it != cell.end() && !it->second->skipped) ran = true;
    (ran ? shown : hidden).push_back(c);
  }
  columns = shown;
  std::string out = "| case | rays |";
  for (const Column& c : columns) out += " " + ColumnName(c) + " |";
  out += "\n| --- | ---: |";
  for (std::size_t i = 0; i < columns.size(); ++i) out += " ---: |";
  out += "\n";
  bool anyFailure = false;
  for (const std::string& row : rows) {
    std::set<std::uint64_t> counts;
    for (const Column& c : columns)
      if (auto it = cell.find({row, c}); it != cell.end() && !it->second->skipped && it->second->rays > 0)
        counts.insert(it->second->rays);
    std::string rays;
    for (std::uint64_t n : counts) rays += (rays.empty() ? "" : "/") + std::to_string(n);
    out += fmt::format("| {} | {} |", row, rays.empty() ? "-" : rays);
    for (const Column& c : columns) {
      auto it = cell.find({row, c});
      if (it == cell.end()) {
        out += " n/a |";
        continue;
      }
      const HardCaseResult& r = *it->second;
      if (r.skipped) {
        out += " skip |";
        continue;
      }
      std::string v = r.rays == 0 ? "ok" : std::to_string(r.wrong);
      if (r.required && r.wrong > 0) {
        v = "**" + v + "**";
        anyFailure = true;
      }
      out += " " + v + " |";
    }
    out += "\n";
  }
  out += "\nCells: rays answered wrong (closest or occlusion); **bold**: a required combination that failed; "
         "ok: an expected error, no rays; n/a: the case does not apply to that structure; skip: not available "
         "here.\n";
  if (!hidden.empty()) {
    std::vector<std::string> names;
    for (const Column& c : hidden) {
      const std::string n = fmt::format("{} {}", BackendName(std::get<1>(c)), PrecisionName(std::get<2>(c)));
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    out += "Not shown (nothing ran, see the notes): " + list + ".\n";
  }
  if (!anyFailure) out += "Every required combination (robust, fp64) has 0 wrong.\n";

  // Notes: skips by reason, then per case the notes of its combinations.
  std::map<std::string, std::set<std::string>> skips;
  for (const HardCaseResult& r : results)
    if (r.skipped) skips[r.note].insert(fmt::format("{} {}", BackendName(r.backend), PrecisionName(r.precision)));
  std::string notes;
  for (const auto& [why, combos] : skips) {
    std::string list;
    for (const std::string& s : combos) list += (list.empty() ? "" : ", ") + s;
    notes += fmt::format("- {}: {}\n", list, why);
  }
  for (const std::string& row : rows) {
    std::map<std::string, std::vector<std::string>> byNote;
    for (const HardCaseResult& r : results)
      if (r.caseName == row && !r.skipped && !r.note.empty() &&
          (r.wrong > 0 || r.rays == 0 || r.note.find("warning") != std::string::npos)) {
        // Failures that are only reported: their first wrong ray is enough.
        std::string note = r.note;
        if (!r.required) note = note.substr(0, note.find("; ray "));
        byNote[note.substr(0, 600)].push_back(ColumnName({r.accel, r.backend, r.precision}));
      }
    for (const auto& [note, cols] : byNote) {
      std::string list = cols.size() > 3 ? fmt::format("{} combinations", cols.size()) : "";
      if (list.empty())
        for (const std::string& s : cols) list += (list.empty() ? "" : ", ") + s;
      notes += fmt::format("- {} ({}): {}\n", row, list, note);
    }
  }
  if (!notes.empty()) out += "\nNotes:\n\n" + notes;
  return out;
}

std::string HardCasesMarkdown()
{
  std::string out;
  std::string family;
  for (const hard::CaseSpec& s : hard::CaseSpecs()) {
    if (s.family != family) {
      family = s.family;
      out += fmt::format("\n### {}\n\n", family);
    }
    out += fmt::format("- **{}**{}: {}\n", s.name, s.perAccel ? " (generated per structure)" : "", s.description);
  }
  return out;
}

std::string HardReportMarkdown(const std::vector<HardCaseResult>& results, const std::string& command, double seconds)
{
  std::uint64_t rays = 0;
  for (const auto& r : results) rays += r.rays;
  return "# Hard cases\n\n"
         "Generated by `" + command +
         "` (tests/hard/gen/hard_gen_*.cpp; rules in tests/hard/gen/hard_cases.h). Every case is a scene and a "
         "ray set made by code from fixed seeds, with an exact expectation per ray; a ray is wrong when "
         "its closest-hit or occlusion answer breaks it. \"The reference's answer\" means `cellray check`'s verdict with "
         "its tolerance, which belongs to the ray and its hit, 2^-16 (|o| + t |d|), never to the scene's or the "
         "primitive's size; hit/miss flips pass only when explained by marginal geometry (docs/TOLERANCE.md). Robust "
         "and fp64 must show 0. The test suite (tests/hard/) runs the same cases at reduced size and asserts it.\n\n"
         "## Cases\n" +
         HardCasesMarkdown() + "\n## Wrong rays\n\n" + HardTableMarkdown(results) +
         fmt::format("\n{} rays judged over all combinations in {:.0f} s.\n", rays, seconds);
}

}  // namespace cr
