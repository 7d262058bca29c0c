// Shared by the libFuzzer targets: a private temporary directory for readers
// that take a path, and the one rule every target follows: cr::InputError is
// the normal answer to bad input; anything else that escapes (another
// exception, a crash, a sanitizer report, a broken invariant) is a finding.
#pragma once

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "host/core/error.h"
#include "host/scene/scene.h"

namespace cr::fuzz {

// A directory of this process's own, removed at exit (left behind only when
// the process dies on a finding).
inline const std::string& TempDir()
{
  static const std::string dir = [] {
    std::string tmpl = (std::filesystem::temp_directory_path() / "cellray_fuzz_XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
      std::perror("cellray fuzz: mkdtemp");
      std::abort();
    }
    static std::string removeAtExit = tmpl;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(removeAtExit, ec);
    });
    return tmpl;
  }();
  return dir;
}

inline std::string WriteTemp(const std::string& name, std::string_view bytes)
{
  std::string path = TempDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    std::fprintf(stderr, "cellray fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// A broken invariant is a finding: say which and abort (libFuzzer saves the input).
[[noreturn]] inline void Fail(const char* what, const std::string& detail = {})
{
  std::fprintf(stderr, "cellray fuzz: invariant broken: %s %s\n", what, detail.c_str());
  std::abort();
}

// Every diagnostic about input names its file: the message must start with
// one of the paths the reader was given.
inline void CheckMessage(const InputError& e, std::string_view path1, std::string_view path2 = {})
{
  std::string_view msg = e.what();
  bool named = msg.substr(0, path1.size()) == path1 || (!path2.empty() && msg.substr(0, path2.size()) == path2);
  if (!named) Fail("InputError does not name the file:", e.what());
}

// The scene model's own invariants (scene/scene.h): every primitive id has
// one PrimInfo, its pieces lie inside the per-type arrays and report its id,
// and every value the backends will read is a finite float.
inline void CheckScene(const Scene& s)
{
  auto finite3 = [](const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); };
  const PrimRanges ranges = s.Ranges();
  for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
    if (s.pieceIds[k].size() != Prim_Count(&ranges, k)) Fail("per-type id arrays differ in length from their primitives");
  if (!s.triNormals.empty() && s.triNormals.size() != s.triangles.size()) Fail("triNormals not one per triangle");
  std::size_t pieces = 0;
  for (std::uint32_t id = 0; id < s.NumPrims(); ++id) {
    const PrimInfo& p = s.prims[id];
    if (p.material >= s.materials.size()) Fail("material index out of range");
    if (p.type >= CR_NUM_PRIM_TYPES) Fail("type out of range");
    const std::vector<std::uint32_t>* ids = &s.pieceIds[p.type];
    if (std::size_t(p.firstPiece) + p.nPieces > ids->size()) Fail("pieces out of range");
    // A CSG leaf (part k of its solid's piece): the piece reports the
    // solid's first leaf, id - k; only part 0 counts the piece.
    for (std::uint32_t k = 0; k < p.nPieces; ++k)
      if ((*ids)[p.firstPiece + k] != id - p.part) Fail("a piece reports another id");
    if (p.part == 0) pieces += p.nPieces;
  }
  if (pieces != s.NumUnified()) Fail("pieces do not add up to the primitives");
  for (const Sphere& sp : s.spheres)
    if (!finite3(sp.center) || !(sp.radius > 0.0f) || !std::isfinite(sp.radius)) Fail("bad sphere");
  for (const Triangle& t : s.triangles)
    if (!finite3(t.v0) || !finite3(t.v1) || !finite3(t.v2)) Fail("non-finite triangle vertex");
  for (const Cone& c : s.cones)
    if (!finite3(c.base) || !finite3(c.apex) || !std::isfinite(c.baseRadius) || !std::isfinite(c.apexRadius))
      Fail("non-finite cone");
}

}  // namespace cr::fuzz
