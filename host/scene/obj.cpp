// OBJ reader: geometry through tinyobjloader, camera and lights from the
// NFF-style NAME.view beside NAME.obj. tinyobjloader does not report line
// numbers and reads a malformed number as 0, so a light validation pass runs
// first: it rejects what tinyobjloader would silently accept, with FILE:LINE,
// and records every `f` line (a face's id is its position among them).
// tinyobjloader trusts every face index it reads, so it must read exactly the
// lines that were validated: the pass hands it the text as validated (one
// '\n' per line, comments cut off), not the file.
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/scene/scene.h"

namespace cr {

namespace {

struct FaceLine {
  std::uint32_t line;
  std::uint32_t nVerts;
};

std::vector<std::string_view> Split(std::string_view s)
{
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    std::size_t b = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\r') ++i;
    if (i > b) out.push_back(s.substr(b, i - b));
  }
  return out;
}

bool ParseInt(std::string_view s, long& v)
{
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

void CheckNumber(std::string_view tok, const std::string& path, long line, const char* what)
{
  std::string_view s = tok;
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  double v = 0.0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || s.empty())
    throw InputError(path, line, fmt::format("expected a number for {}, got '{}'", what, tok));
  if (!std::isfinite(v) || std::fabs(v) > double(std::numeric_limits<float>::max()))
    throw InputError(path, line, fmt::format("{} '{}' is not a finite float", what, tok));
}

// Validates the text; returns the face lines in order, and in `clean` the
// text for tinyobjloader. Lines end as tinyobjloader ends them ("\n", "\r\n"
// or a lone "\r"); a comment runs from '#' to the end of its line, where
// tinyobjloader knows only whole-line comments and would read the rest of
// "f 1 2 3#x 9" as more vertex references, unchecked.
std::vector<FaceLine> Validate(std::string_view text, const std::string& path, std::string& clean)
{
  std::vector<FaceLine> faces;
  long nV = 0, nVT = 0, nVN = 0;
  long line = 0;
  std::set<std::string> warned;
  clean.clear();
  clean.reserve(text.size() + 1);
  std::size_t pos = 0;
  while (pos < text.size()) {
    ++line;
    std::size_t e = text.find_first_of("\r\n", pos);
    if (e == std::string_view::npos) e = text.size();
    std::string_view ln = text.substr(pos, e - pos);
    pos = e + 1;
    if (e + 1 < text.size() && text[e] == '\r' && text[e + 1] == '\n') ++pos;
    if (auto h = ln.find('#'); h != std::string_view::npos) ln = ln.substr(0, h);
    // tinyobjloader reads C strings: a NUL would end its line early.
    if (ln.find('\0') != std::string_view::npos) throw InputError(path, line, "NUL byte: not a text file");
    clean.append(ln);
    clean.push_back('\n');
    auto tok = Split(ln);
    if (tok.empty()) continue;
    const std::string_view kw = tok[0];
    if (kw == "v") {
      if (tok.size() < 4) throw InputError(path, line, fmt::format("'v' needs 3 coordinates, got {}", tok.size() - 1));
      for (std::size_t i = 1; i < tok.size() && i <= 7; ++i) CheckNumber(tok[i], path, line, "a vertex coordinate");
      ++nV;
    } else if (kw == "vt" || kw == "vn") {
      std::size_t need = kw == "vt" ? 1 : 3;
      if (tok.size() < need + 1) throw InputError(path, line, fmt::format("'{}' needs {} numbers", kw, need));
      for (std::size_t i = 1; i < tok.size() && i <= 3; ++i) CheckNumber(tok[i], path, line, "a component");
      (kw == "vt" ? nVT : nVN)++;
    } else if (kw == "f") {
      for (std::size_t i = 1; i < tok.size(); ++i) {
        std::string_view ref = tok[i];
        long counts[3] = {nV, nVT, nVN};
        for (int part = 0; part < 3; ++part) {
          std::size_t slash = ref.find('/');
          std::string_view num = ref.substr(0, slash);
          if (!(part > 0 && num.empty())) {
            long idx = 0;
            if (!ParseInt(num, idx) || idx == 0)
              throw InputError(path, line, fmt::format("'f': bad vertex reference '{}'", tok[i]));
            long resolved = idx > 0 ? idx - 1 : counts[part] + idx;
            if (resolved < 0 || resolved >= counts[part])
              throw InputError(path, line,
                               fmt::format("'f': {} index {} is out of range (1..{} defined so far)",
                                           part == 0 ? "vertex" : (part == 1 ? "texture" : "normal"), idx, counts[part]));
          }
          if (slash == std::string_view::npos) break;
          ref = ref.substr(slash + 1);
          if (part == 2) throw InputError(path, line, fmt::format("'f': bad vertex reference '{}'", tok[i]));
        }
      }
      if (faces.size() >= std::numeric_limits<std::uint32_t>::max() - 1)
        throw InputError(path, line, "too many faces");
      faces.push_back({static_cast<std::uint32_t>(line), static_cast<std::uint32_t>(tok.size() - 1)});
    } else if (kw == "o" || kw == "g" || kw == "s" || kw == "usemtl" || kw == "mtllib" || kw == "l" || kw == "p") {
      // Grouping, smoothing, materials, lines and points: not geometry here.
    } else if (warned.insert(std::string(kw)).second) {
      Warn(fmt::format("{}:{}: unsupported statement '{}' ignored", path, line, kw));
    }
  }
  return faces;
}

}  // namespace

Scene LoadOBJ(const std::string& path)
{
  std::vector<char> data = ReadFile(path);
  std::string text(data.data(), data.size());
  data.clear();
  data.shrink_to_fit();
  std::string clean;
  std::vector<FaceLine> faces = Validate(text, path, clean);
  if (faces.empty()) throw InputError(path, 0, text.empty() ? "empty scene file" : "no geometry: the file has no 'f' line");
  text.clear();
  text.shrink_to_fit();

  Scene scene;
  scene.path = path;
  scene.materials.push_back(Material{});

  // Camera, lights and background from NAME.view.
  std::filesystem::path view = std::filesystem::path(path).replace_extension(".view");
  std::error_code ec;
  if (std::filesystem::exists(view, ec)) {
    std::vector<char> vtext = ReadFile(view.string());
    ParseNFF(std::string_view(vtext.data(), vtext.size()), view.string(), scene, true);
  } else {
    Warn(fmt::format("{}: no view file {}: the camera will frame the bounding box", path, view.string()));
  }

  tinyobj::ObjReaderConfig config;
  config.triangulate = false;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(clean, "", config))
    throw InputError(path, 0, fmt::format("tinyobjloader: {}", reader.Error()));
  clean.clear();
  clean.shrink_to_fit();
  const auto& verts = reader.GetAttrib().vertices;

  // tinyobjloader drops faces of fewer than 3 vertices and stores face sizes in
  // a byte; the validated face list gives the true sizes and ids.
  std::size_t fi = 0;
  auto skipDegenerate = [&]() {
    while (fi < faces.size() && faces[fi].nVerts < 3) {
      PrimInfo info;
      info.kind = PrimKind::kFace;
      info.type = CR_PRIM_TRIANGLE;
      info.line = faces[fi].line;
      Warn(fmt::format("{}:{}: face with {} vertices: skipped, id {} kept", path, faces[fi].line, faces[fi].nVerts,
                       scene.NumPrims()));
      scene.prims.push_back(info);
      ++fi;
    }
  };
  std::vector<glm::dvec3> poly;
  long zeroArea = 0, firstZeroLine = 0;
  for (const auto& shape : reader.GetShapes()) {
    const auto& idx = shape.mesh.indices;
    std::size_t k = 0;
    while (k < idx.size()) {
      skipDegenerate();
      if (fi >= faces.size()) break;
      const FaceLine f = faces[fi++];
      if (k + f.nVerts > idx.size()) break;
      poly.clear();
      for (std::uint32_t j = 0; j < f.nVerts; ++j) {
        int vi = idx[k + j].vertex_index;
        // Validate checked every index; this guards the read should tinyobjloader ever see another one.
        if (vi < 0 || std::size_t(vi) >= verts.size() / 3)
          throw RuntimeError(fmt::format("{}:{}: tinyobjloader read vertex index {} of {}", path, f.line, vi + 1,
                                         verts.size() / 3));
        poly.emplace_back(verts[3 * std::size_t(vi)], verts[3 * std::size_t(vi) + 1], verts[3 * std::size_t(vi) + 2]);
      }
      k += f.nVerts;
      if (!AddPolygon(scene, PrimKind::kFace, poly, nullptr, 0, f.line, path, /*warnIfDegenerate=*/false)) {
        if (zeroArea++ == 0) firstZeroLine = f.line;
      }
    }
    if (k != idx.size()) {
      throw RuntimeError(fmt::format("{}: tinyobjloader's faces do not match the file's 'f' lines", path));
    }
  }
  skipDegenerate();
  if (fi != faces.size())
    throw RuntimeError(fmt::format("{}: tinyobjloader returned {} of {} faces", path, fi, faces.size()));
  if (zeroArea)
    Warn(fmt::format("{}: {} zero-area faces skipped, ids kept (first on line {})", path, zeroArea, firstZeroLine));

  if (!scene.hasCamera) {
    // Frame the bounding box: look at its centre from the +z side.
    Bounds b = scene.WorldBounds();
    glm::vec3 c = 0.5f * (b.lo + b.hi);
    float r = 0.5f * glm::length(b.Extent());
    scene.camera.at = c;
    scene.camera.from = c + glm::vec3(0.0f, 0.0f, 2.5f * r);
    scene.camera.up = glm::vec3(0.0f, 1.0f, 0.0f);
    scene.camera.angle = 45.0f;
    scene.camera.hither = 0.0f;
    scene.hasCamera = true;
  }
  if (scene.lights.empty()) scene.lights.push_back(Light{scene.camera.from, glm::vec3(1.0f)});
  return scene;
}

}  // namespace cr
