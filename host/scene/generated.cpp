#include "host/scene/generated.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/scene/generate.h"

namespace cr {

namespace {

namespace fs = std::filesystem;

// The generators' kinds (gen:KIND:N).
const std::string_view kGenKinds[] = {"sphereflake", "bumpy", "stadium", "quadrics", "polyhedra", "sdf", "csg"};
// gen:subdiv-MESH:N, a real mesh subdivided to N triangles (SubdivideMesh).
const std::string kSubdiv = "subdiv-";

bool IsSourceTree(const fs::path& p)
{
  std::error_code ec;
  return fs::is_directory(p / "scenes" / "spd", ec) && fs::is_regular_file(p / "bench" / "plot.py", ec);
}

struct GeneratedName {
  std::string kind;
  std::uint64_t n = 0;
};

GeneratedName ParseGenerated(const std::string& name)
{
  if (!IsGeneratedName(name)) throw InputError(fmt::format("scene '{}': not a generated scene (gen:KIND:N)", name));
  const auto colon = name.find(':', 4);
  if (colon == std::string::npos) throw InputError(fmt::format("scene '{}': expected gen:KIND:N", name));
  GeneratedName p;
  p.kind = name.substr(4, colon - 4);
  const std::string num = name.substr(colon + 1);
  auto [end, ec] = std::from_chars(num.data(), num.data() + num.size(), p.n);
  if (ec != std::errc() || end != num.data() + num.size())
    throw InputError(fmt::format("scene '{}': '{}' is not a number", name, num));
  if (p.kind.rfind(kSubdiv, 0) == 0) {
    if (MeshPath(p.kind.substr(kSubdiv.size())).empty())
      throw InputError(fmt::format("scene '{}': no mesh ../shared/scenes/meshes/{}.obj beside the source tree", name,
                                   p.kind.substr(kSubdiv.size())));
  } else if (std::find(std::begin(kGenKinds), std::end(kGenKinds), p.kind) == std::end(kGenKinds)) {
    throw InputError(fmt::format("scene '{}': generated kinds are {}", name, GeneratedKinds()));
  }
  return p;
}

}  // namespace

bool IsGeneratedName(std::string_view name) { return name.rfind("gen:", 0) == 0; }

std::string GeneratedKinds()
{
  std::string s;
  for (std::string_view k : kGenKinds) {
    if (!s.empty()) s += '|';
    s += k;
  }
  return s + '|' + kSubdiv + "MESH";
}

std::string GeneratedShortName(const std::string& name)
{
  const GeneratedName p = ParseGenerated(name);
  return fmt::format("{}-{}", p.kind, p.n);
}

namespace {
Scene Generate(const GeneratedName& p)
{
  const std::uint64_t n = p.n;
  if (p.kind.rfind(kSubdiv, 0) == 0) return SubdivideMesh(LoadScene(MeshPath(p.kind.substr(kSubdiv.size()))), n);
  if (p.kind == "sphereflake") return GenerateSphereflake(static_cast<int>(std::min<std::uint64_t>(n, 100)));
  if (p.kind == "bumpy") return GenerateBumpySphere(n);
  if (p.kind == "quadrics") return GenerateQuadricField(n);
  if (p.kind == "polyhedra") return GeneratePolyhedronField(n);
  if (p.kind == "sdf") return GenerateSdfField(n);
  if (p.kind == "csg") return GenerateCsgField(n);
  return GenerateStadium(static_cast<int>(std::min<std::uint64_t>(n, 100)));
}
}  // namespace

Scene LoadGenerated(const std::string& name)
{
  Scene scene = Generate(ParseGenerated(name));
  scene.path = name;  // what the scene is called in messages and reprs
  return scene;
}

std::string FindSourceRoot()
{
  std::error_code ec;
  std::vector<fs::path> starts = {fs::current_path(ec)};
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) starts.push_back(exe.parent_path());
  for (fs::path p : starts) {
    for (int up = 0; up < 6 && !p.empty(); ++up) {
      if (IsSourceTree(p)) return fs::weakly_canonical(p, ec).string();
      if (p == p.parent_path()) break;
      p = p.parent_path();
    }
  }
  return "";
}

std::string MeshDir(const std::string& root)
{
  return root.empty() ? "" : (fs::path(root) / ".." / "shared" / "scenes" / "meshes").lexically_normal().string();
}

std::string MeshPath(const std::string& name)
{
  const std::string dir = MeshDir(FindSourceRoot());
  std::error_code ec;
  if (dir.empty() || name.empty() || name.find('/') != std::string::npos) return "";
  const fs::path p = fs::path(dir) / (name + ".obj");
  return fs::is_regular_file(p, ec) ? p.string() : "";
}

}  // namespace cr
