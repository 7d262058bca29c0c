#include "host/bench/bench_scenes.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <system_error>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/scene/generate.h"

namespace cr::bench {

namespace {
// The kinds LoadBenchScene generates (gen:KIND:N).
const std::string_view kGenKinds[] = {"sphereflake", "bumpy", "stadium", "quadrics", "polyhedra", "sdf", "csg"};
// gen:subdiv-MESH:N, a real mesh subdivided to N triangles (SubdivideMesh).
const std::string kSubdiv = "subdiv-";
}  // namespace

std::string GeneratedKinds()
{
  std::string s;
  for (std::string_view k : kGenKinds) {
    if (!s.empty()) s += '|';
    s += k;
  }
  return s + '|' + kSubdiv + "MESH";
}

namespace fs = std::filesystem;

namespace {

bool IsSourceRoot(const fs::path& p)
{
  std::error_code ec;
  return fs::is_directory(p / "scenes" / "spd", ec) && fs::is_regular_file(p / "bench" / "plot.py", ec);
}

std::string MeshDir(const std::string& root) { return root.empty() ? "" : (fs::path(root) / ".." / "shared" / "scenes" / "meshes").lexically_normal().string(); }

// Parses gen:KIND:N.
std::optional<SceneRef> GeneratedRef(const std::string& name)
{
  if (name.rfind("gen:", 0) != 0) return std::nullopt;
  const auto colon = name.find(':', 4);
  if (colon == std::string::npos) throw InputError(fmt::format("scene '{}': expected gen:KIND:N", name));
  const std::string kind = name.substr(4, colon - 4);
  const std::string num = name.substr(colon + 1);
  std::uint64_t n = 0;
  auto [p, ec] = std::from_chars(num.data(), num.data() + num.size(), n);
  if (ec != std::errc() || p != num.data() + num.size())
    throw InputError(fmt::format("scene '{}': '{}' is not a number", name, num));
  if (kind.rfind(kSubdiv, 0) == 0) {
    if (MeshPath(kind.substr(kSubdiv.size())).empty())
      throw InputError(fmt::format("scene '{}': no mesh ../shared/scenes/meshes/{}.obj beside the source tree", name,
                                   kind.substr(kSubdiv.size())));
  } else if (std::find(std::begin(kGenKinds), std::end(kGenKinds), kind) == std::end(kGenKinds)) {
    throw InputError(fmt::format("scene '{}': generated kinds are {}", name, GeneratedKinds()));
  }
  return SceneRef{fmt::format("{}-{}", kind, n), name, name, true};
}

// A path relative to the source tree (scenes/spd/x.nff,
// ../shared/scenes/meshes/x.obj) when it lies inside it or beside it, so that
// results do not record where this checkout happens to live.
std::string Shown(const std::string& path, const std::string& root)
{
  if (root.empty()) return path;
  std::error_code ec;
  const fs::path abs = fs::weakly_canonical(path, ec);
  if (ec) return path;
  const fs::path rel = abs.lexically_relative(fs::path(root).parent_path());
  if (rel.empty() || *rel.begin() == "..") return path;
  return abs.lexically_relative(root).string();
}

}  // namespace

std::string MeshPath(const std::string& name)
{
  const std::string dir = MeshDir(FindSourceRoot());
  std::error_code ec;
  if (dir.empty() || name.empty() || name.find('/') != std::string::npos) return "";
  const fs::path p = fs::path(dir) / (name + ".obj");
  return fs::is_regular_file(p, ec) ? p.string() : "";
}

std::string FindSourceRoot()
{
  std::error_code ec;
  std::vector<fs::path> starts = {fs::current_path(ec)};
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) starts.push_back(exe.parent_path());
  for (fs::path p : starts) {
    for (int up = 0; up < 6 && !p.empty(); ++up) {
      if (IsSourceRoot(p)) return fs::weakly_canonical(p, ec).string();
      if (p == p.parent_path()) break;
      p = p.parent_path();
    }
  }
  return "";
}

const std::vector<std::string>& DefaultSpdScenes()
{
  static const std::vector<std::string> names = {"balls", "gears", "mount", "rings", "teapot", "tetra", "tree"};
  return names;
}

std::vector<SceneRef> ResolveScenes(const std::vector<std::string>& names, std::vector<std::string>& notes)
{
  const std::string root = FindSourceRoot();
  const std::string meshDir = MeshDir(root);
  std::vector<SceneRef> out;
  std::error_code ec;
  if (names.empty()) {
    if (root.empty())
      throw InputError("bench: no scenes given and the source tree (scenes/spd/) was not found from the working "
                       "directory or the executable; name scene files on the command line");
    for (const auto& n : DefaultSpdScenes())
      out.push_back(SceneRef{n, (fs::path(root) / "scenes" / "spd" / (n + ".nff")).string(), "", false});
    if (!meshDir.empty() && fs::is_directory(meshDir, ec)) {
      std::vector<std::string> meshes;
      for (const auto& e : fs::directory_iterator(meshDir, ec))
        if (e.path().extension() == ".obj") meshes.push_back(e.path().stem().string());
      std::sort(meshes.begin(), meshes.end());
      for (const auto& m : meshes) out.push_back(SceneRef{m, (fs::path(meshDir) / (m + ".obj")).string(), "", false});
    } else {
      notes.push_back("meshes skipped: ../shared/scenes/meshes/ (beside the source tree) does not exist");
    }
    for (auto& r : out) r.shown = Shown(r.path, root);
    return out;
  }
  for (const auto& n : names) {
    if (auto g = GeneratedRef(n)) {
      out.push_back(*g);
      continue;
    }
    if (fs::is_regular_file(n, ec)) {
      out.push_back(SceneRef{fs::path(n).stem().string(), n, Shown(n, root), false});
      continue;
    }
    std::vector<fs::path> candidates;
    if (!root.empty()) candidates.push_back(fs::path(root) / "scenes" / "spd" / (n + ".nff"));
    if (!meshDir.empty()) candidates.push_back(fs::path(meshDir) / (n + ".obj"));
    bool found = false;
    for (const auto& c : candidates)
      if (fs::is_regular_file(c, ec)) {
        out.push_back(SceneRef{n, c.string(), Shown(c.string(), root), false});
        found = true;
        break;
      }
    if (!found)
      throw InputError(fmt::format("unknown scene '{}': not a file, not an SPD scene (scenes/spd/{}.nff), not a mesh "
                                   "(../shared/scenes/meshes/{}.obj), not gen:{}:N",
                                   n, n, n, GeneratedKinds()));
  }
  return out;
}

Scene LoadBenchScene(const SceneRef& ref)
{
  if (!ref.generated) return LoadScene(ref.path);
  const auto colon = ref.path.find(':', 4);
  const std::string kind = ref.path.substr(4, colon - 4);
  const std::uint64_t n = std::stoull(ref.path.substr(colon + 1));
  if (kind.rfind(kSubdiv, 0) == 0) {
    const std::string mesh = MeshPath(kind.substr(kSubdiv.size()));
    if (mesh.empty()) throw InputError(fmt::format("scene '{}': mesh not found", ref.path));
    return SubdivideMesh(LoadScene(mesh), n);
  }
  if (kind == "sphereflake") return GenerateSphereflake(static_cast<int>(std::min<std::uint64_t>(n, 100)));
  if (kind == "bumpy") return GenerateBumpySphere(n);
  if (kind == "quadrics") return GenerateQuadricField(n);
  if (kind == "polyhedra") return GeneratePolyhedronField(n);
  if (kind == "sdf") return GenerateSdfField(n);
  if (kind == "csg") return GenerateCsgField(n);
  return GenerateStadium(static_cast<int>(std::min<std::uint64_t>(n, 100)));
}

}  // namespace cr::bench
