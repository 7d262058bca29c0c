#include "host/bench/report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr::bench {

using nlohmann::json;

namespace {

double Num(const json& j, const char* key, double fallback = 0.0)
{
  if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return fallback;
  return j[key].get<double>();
}

std::string Str(const json& j, const char* key)
{
  if (!j.is_object() || !j.contains(key) || !j[key].is_string()) return "";
  return j[key].get<std::string>();
}

bool Timed(const json& r) { return r.contains("mrays_per_s") && r["mrays_per_s"].is_object(); }
double Mrays(const json& r) { return Timed(r) ? Num(r["mrays_per_s"], "median") : 0.0; }

// Ours and exact: robust-mode rows of our backends (what the comparison with
// Embree counts as ours; fast mode may answer wrongly, fp64 is a reference).
bool OursRobust(const json& r)
{
  const std::string b = Str(r, "backend");
  return b != "embree" && b != "reference" && Str(r, "precision") == "robust";
}

std::string Sci(double x) { return x == 0.0 ? "0" : fmt::format("{:.1e}", x); }
std::string F(double x, int digits = 2) { return fmt::format("{:.{}f}", x, digits); }
std::string MiB(double bytes) { return fmt::format("{:.2f}", bytes / (1024.0 * 1024.0)); }
// The structure's bytes per primitive (its arrays over the scene's pieces).
std::string BytesPerPrim(const json& r)
{
  const double n = Num(r, "pieces");
  return n > 0.0 ? fmt::format("{:.0f}", Num(r, "bytes") / n) : std::string("–");
}

std::vector<std::string> Ordered(const json& rows, const char* key, bool (*keep)(const json&) = nullptr)
{
  std::vector<std::string> out;
  std::set<std::string> seen;
  for (const auto& r : rows) {
    if (keep && !keep(r)) continue;
    const std::string v = Str(r, key);
    if (seen.insert(v).second) out.push_back(v);
  }
  return out;
}

bool PivotColumn(const json& r) { return OursRobust(r) || Str(r, "backend") == "embree"; }

// What the header describes: the main run, or (a --scaling or --hard run
// on its own) that study, which keeps its machine, command and options in
// its own section.
const json& HeaderSource(const json& res)
{
  if (!res.contains("machine"))
    for (const char* study : {"scaling", "hard"})
      if (res.contains(study) && res[study].is_object() && res[study].contains("machine")) return res[study];
  return res;
}

std::string Header(const json& results)
{
  const json& res = HeaderSource(results);
  const json& m = res.contains("machine") ? res["machine"] : json::object();
  std::string s = "# cellray bench results\n\n";
  s += fmt::format("- date: {}, commit `{}`\n", Str(m, "date"), Str(m, "git_commit"));
  s += fmt::format("- machine: {}, {} hardware threads, governor: {}, SIMD {}, Embree {}\n", Str(m, "cpu_model"),
                   Num(m, "hardware_threads"), Str(m, "governor"), Str(m, "simd_isa"),
                   m.contains("embree") && m["embree"].is_string() ? m["embree"].get<std::string>() : "absent");
  if (res.contains("command")) s += fmt::format("- command: `{}`\n", Str(res, "command"));
  if (res.contains("options")) {
    const json& o = res["options"];
    s += fmt::format("- rays per set: {}, timed runs per row: {} (median; min and max given), threads: {}\n",
                     Num(o, "rays"), Num(o, "repeat"), Num(o, "threads"));
  }
  if (results.contains("load_average")) {
    s += fmt::format("- load average (1 min) at start / end: {} / {} (timings with a load above the core count "
                     "are noise)\n",
                     F(Num(results["load_average"], "start")), F(Num(results["load_average"], "end")));
  }
  if (results.contains("wall_s")) s += fmt::format("- wall time of the run: {:.0f} s\n", Num(results, "wall_s"));
  if (results.contains("notes"))
    for (const auto& n : results["notes"]) s += fmt::format("- note: {}\n", n.get<std::string>());
  return s + "\n";
}

std::string PivotTable(const json& rows)
{
  const auto cols = Ordered(rows, "label", &PivotColumn);
  if (cols.empty()) return "";
  std::map<std::pair<std::string, std::string>, std::map<std::string, double>> cell;
  std::vector<std::pair<std::string, std::string>> keys;
  for (const auto& r : rows) {
    if (!PivotColumn(r)) continue;
    auto key = std::make_pair(Str(r, "scene"), Str(r, "kind"));
    if (!cell.count(key)) keys.push_back(key);
    cell[key][Str(r, "label")] = Mrays(r);
  }
  std::string s = "## Mrays/s (median), robust configurations and Embree\n\n| scene | rays |";
  for (const auto& c : cols) s += " " + c + " |";
  s += "\n| --- | --- |";
  for (std::size_t i = 0; i < cols.size(); ++i) s += " ---: |";
  s += "\n";
  for (const auto& k : keys) {
    // The fastest of the row in bold.
    double best = 0.0;
    for (const auto& [l, v] : cell[k]) best = std::max(best, v);
    s += fmt::format("| {} | {} |", k.first, k.second);
    for (const auto& c : cols) {
      auto it = cell[k].find(c);
      if (it == cell[k].end() || it->second <= 0.0)
        s += " – |";
      else
        s += it->second == best ? fmt::format(" **{}** |", F(it->second)) : fmt::format(" {} |", F(it->second));
    }
    s += "\n";
  }
  return s + "\n";
}

std::string SpeedErrorTable(const json& rows)
{
  struct Acc {
    std::string precision;
    double logSum = 0.0;
    int n = 0;
    std::uint64_t wrong = 0, flips = 0, rays = 0;
    double maxRel = 0.0, meanRelWeighted = 0.0, weight = 0.0;
  };
  std::map<std::string, Acc> acc;
  std::vector<std::string> order;
  for (const auto& r : rows) {
    if (!Timed(r) || !r["error"].is_object()) continue;
    const std::string l = Str(r, "label");
    if (!acc.count(l)) order.push_back(l);
    Acc& a = acc[l];
    a.precision = Str(r, "precision");
    const double m = Mrays(r);
    if (m > 0.0) {
      a.logSum += std::log(m);
      ++a.n;
    }
    const json& e = r["error"];
    a.wrong += static_cast<std::uint64_t>(Num(e, "wrong"));
    a.flips += static_cast<std::uint64_t>(Num(e, "flips"));
    a.rays += static_cast<std::uint64_t>(Num(r, "rays"));
    a.maxRel = std::max(a.maxRel, Num(e, "max_rel_t_err"));
    const double agree = Num(e, "agree");
    a.meanRelWeighted += Num(e, "mean_rel_t_err") * agree;
    a.weight += agree;
  }
  if (order.empty()) return "";
  std::string s =
      "## Speed against error, per configuration\n\nGeometric mean of the median Mrays/s over every scene and ray "
      "kind; wrong answers and hit/miss flips explained by marginal geometry summed over the same rows "
      "(reference/check.h, docs/TOLERANCE.md); relative t error of the agreeing closest hits (max, and mean weighted "
      "by agreeing rays).\n\n"
      "| configuration | precision | Mrays/s (geo. mean) | wrong | wrong rate | flips | max rel. t error | mean rel. t "
      "error |\n"
      "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& l : order) {
    const Acc& a = acc[l];
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |\n", l, a.precision,
                     a.n ? F(std::exp(a.logSum / a.n)) : "–", a.wrong,
                     Sci(a.rays ? double(a.wrong) / double(a.rays) : 0.0), a.flips, Sci(a.maxRel),
                     Sci(a.weight > 0.0 ? a.meanRelWeighted / a.weight : 0.0));
  }
  return s + "\n";
}

std::string FullTable(const json& rows, const char* title)
{
  std::string s = fmt::format(
      "## {}\n\n| scene | rays | n | configuration | ran as | build ms | MiB | B/prim | Mrays/s (min–max) | IT/ray | "
      "TS/ray | leaves/ray | empty/ray | wrong | max rel. t err | note |\n"
      "| --- | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
      title);
  for (const auto& r : rows) {
    std::string speed = "–";
    if (Timed(r))
      speed = fmt::format("{} ({}–{})", F(Mrays(r)), F(Num(r["mrays_per_s"], "min")), F(Num(r["mrays_per_s"], "max")));
    std::string it = "–", ts = "–", lv = "–", el = "–";
    if (r.contains("per_ray") && r["per_ray"].is_object()) {
      const json& p = r["per_ray"];
      it = F(Num(p, "intersection_tests"), 1);
      ts = F(Num(p, "traversal_steps"), 1);
      lv = F(Num(p, "leaves_visited"), 1);
      el = F(Num(p, "empty_leaves_visited"), 1);
    }
    std::string wrong = "–", rel = "–";
    if (r.contains("error") && r["error"].is_object()) {
      wrong = fmt::format("{}", Num(r["error"], "wrong"));
      rel = Sci(Num(r["error"], "max_rel_t_err"));
    }
    std::string note = Str(r, "note");
    std::replace(note.begin(), note.end(), '|', '/');
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                     Str(r, "scene"), Str(r, "kind"), Num(r, "rays"), Str(r, "label"), Str(r, "variant_ran"),
                     F(Num(r, "build_ms"), 1), MiB(Num(r, "bytes")), BytesPerPrim(r), speed, it, ts, lv, el, wrong,
                     rel, note);
  }
  return s + "\n";
}

std::string ImageTable(const json& images)
{
  if (!images.is_array() || images.empty()) return "";
  const json& first = images[0];
  std::string s = fmt::format(
      "## Samples per pixel against image error\n\nRenders ({}) of {} at {}x{}, compared after display "
      "encoding with a render by the fp64 reference backend at high spp (PSNR, mean absolute error; for "
      "--diffuse, the path tracer limited to two vertices), and with the "
      "reference's render at the same spp and seed (arithmetic alone; ∞: identical images).\n\n"
      "| configuration | spp | render ms | Mrays/s | PSNR dB | mean abs. error | PSNR same spp | mean abs. error same spp | note |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
      first.contains("integrator") ? Str(first, "integrator") : std::string("whitted"), Str(first, "scene"),
      Num(first, "width"), Num(first, "height"));
  for (const auto& r : images) {
    const double ms = Num(r, "render_ms");
    const std::string same = r["psnr_same_spp"].is_number() ? F(r["psnr_same_spp"].get<double>()) : "∞";
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", Str(r, "label"), Num(r, "spp"), F(ms, 1),
                     ms > 0.0 ? F(Num(r, "rays") / (ms * 1e3)) : "–", F(Num(r, "psnr")), Sci(Num(r, "mean_error")),
                     same, Sci(Num(r, "mean_error_same_spp")), Str(r, "note"));
  }
  return s + "\n";
}

std::string ScalingTable(const json& sc)
{
  if (!sc.is_object() || !sc.contains("rows")) return "";
  const json& rows = sc["rows"];
  struct Cell {
    json primary, diffuse, any;
  };
  std::map<std::pair<std::string, std::string>, Cell> cells;
  std::vector<std::pair<std::string, std::string>> keys;
  for (const auto& r : rows) {
    auto k = std::make_pair(Str(r, "scene"), Str(r, "label"));
    if (!cells.count(k)) keys.push_back(k);
    Cell& c = cells[k];
    c.any = r;
    if (Str(r, "kind") == "primary") c.primary = r;
    if (Str(r, "kind") == "diffuse") c.diffuse = r;
  }
  std::string s =
      "## Scaling with scene size\n\nBuild time, memory (the structure's arrays; peak RSS of the process while that "
      "configuration was built and traced) and time per ray (median) for primary and diffuse rays; IT / TS: "
      "intersection tests and traversal steps per ray.\n\n"
      "| scene | primitives | configuration | build ms | MiB | B/prim | peak RSS MiB | primary ns/ray | diffuse ns/ray | "
      "primary IT / TS | diffuse IT / TS | note |\n"
      "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  auto ns = [](const json& r) {
    if (!r.is_object() || !Timed(r) || Mrays(r) <= 0.0) return std::string("–");
    return F(1e3 / Mrays(r), 1);
  };
  auto itts = [](const json& r) {
    if (!r.is_object() || !r.contains("per_ray") || !r["per_ray"].is_object()) return std::string("–");
    return fmt::format("{} / {}", F(Num(r["per_ray"], "intersection_tests"), 1), F(Num(r["per_ray"], "traversal_steps"), 1));
  };
  for (const auto& k : keys) {
    const Cell& c = cells[k];
    std::string note = Str(c.any, "note");
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", k.first, Num(c.any, "pieces"),
                     k.second, F(Num(c.any, "build_ms"), 1), MiB(Num(c.any, "bytes")), BytesPerPrim(c.any),
                     MiB(Num(c.any, "peak_rss_bytes")), ns(c.primary), ns(c.diffuse), itts(c.primary), itts(c.diffuse),
                     note);
  }
  return s + "\n";
}

}  // namespace

json LoadResults(const std::string& dir)
{
  const auto path = std::filesystem::path(dir) / "results.json";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return json::object();
  try {
    std::ifstream f(path);
    json j = json::parse(f);
    return j.is_object() ? j : json::object();
  } catch (const std::exception&) {
    return json::object();  // an unreadable old record is replaced, never merged
  }
}

void WriteResults(const std::string& dir, const json& results)
{
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw RuntimeError(fmt::format("{}: cannot create directory ({})", dir, ec.message()));
  const std::string text = results.dump(1) + "\n";
  WriteFileAtomically((std::filesystem::path(dir) / "results.json").string(), text.data(), text.size());
  const std::string md = ResultsMarkdown(results);
  WriteFileAtomically((std::filesystem::path(dir) / "results.md").string(), md.data(), md.size());
}

std::string EmbreeComparisonMarkdown(const json& rows, const std::vector<std::string>& kinds)
{
  struct Best {
    std::string label;
    double mrays = 0.0;
  };
  std::map<std::pair<std::string, std::string>, std::pair<Best, Best>> m;  // (scene, kind) -> (ours, embree)
  std::vector<std::string> scenes;
  bool anyEmbree = false;
  for (const auto& r : rows) {
    const std::string kind = Str(r, "kind");
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end() || !Timed(r)) continue;
    const std::string scene = Str(r, "scene");
    if (std::find(scenes.begin(), scenes.end(), scene) == scenes.end()) scenes.push_back(scene);
    auto& [ours, emb] = m[{scene, kind}];
    const double v = Mrays(r);
    if (Str(r, "backend") == "embree") {
      anyEmbree = true;
      if (v > emb.mrays) emb = Best{Str(r, "label"), v};
    } else if (OursRobust(r) && v > ours.mrays) {
      ours = Best{Str(r, "label"), v};
    }
  }
  if (!anyEmbree) return "";
  std::string s = "| scene | rays | our fastest (robust) | Mrays/s | Embree's fastest | Mrays/s | ours ÷ Embree |\n"
                  "| --- | --- | --- | ---: | --- | ---: | ---: |\n";
  for (const auto& scene : scenes)
    for (const auto& kind : kinds) {
      auto it = m.find({scene, kind});
      if (it == m.end()) continue;
      const auto& [ours, emb] = it->second;
      s += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", scene, kind, ours.label, F(ours.mrays), emb.label,
                       F(emb.mrays), emb.mrays > 0.0 && ours.mrays > 0.0 ? F(ours.mrays / emb.mrays) : "–");
    }
  return s;
}

std::string ResultsMarkdown(const json& res)
{
  std::string s = Header(res);
  const json rows = res.contains("rows") ? res["rows"] : json::array();
  const std::string cmp = EmbreeComparisonMarkdown(rows, {"primary", "shadow", "diffuse", "random"});
  if (!cmp.empty())
    s += "## Our fastest against Embree's fastest\n\nOurs: the fastest robust configuration (0 wrong is their "
         "contract); ratio of speeds, >= 1 means ours is faster.\n\n" +
         cmp + "\n";
  s += PivotTable(rows);
  s += SpeedErrorTable(rows);
  if (res.contains("images")) s += ImageTable(res["images"]);
  if (res.contains("scaling")) s += ScalingTable(res["scaling"]);
  if (res.contains("hard") && res["hard"].is_object() && res["hard"].contains("markdown"))
    s += "## Hard cases (`cellray bench --hard`)\n\n" + res["hard"]["markdown"].get<std::string>() + "\n";
  if (!rows.empty()) s += FullTable(rows, "Every row");
  return s;
}

}  // namespace cr::bench
