#include "host/bench/bench_scenes.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <system_error>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/scene/generated.h"

namespace cr::bench {

namespace fs = std::filesystem;

namespace {

// gen:KIND:N, checked (host/scene/generated.h).
std::optional<SceneRef> GeneratedRef(const std::string& name)
{
  if (!IsGeneratedName(name)) return std::nullopt;
  return SceneRef{GeneratedShortName(name), name, name, true};
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

Scene LoadBenchScene(const SceneRef& ref) { return ref.generated ? LoadGenerated(ref.path) : LoadScene(ref.path); }

}  // namespace cr::bench
