#include "host/scene/scene.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/generated.h"
#include "host/scene/triangulate.h"

namespace cr {

const char* PrimTypeName(std::uint32_t k)
{
#define CR_TYPE_NAME_(T, U, a) \
  if (k == CR_PRIM_##U) return PrimTypeName(PrimTag<T>{});
  CR_PRIM_TYPES(CR_TYPE_NAME_)
#undef CR_TYPE_NAME_
  return "?";
}

const char* PrimInfoName(const PrimInfo& info)
{
  switch (info.kind) {
    case PrimKind::kShape: return PrimTypeName(info.type);
    case PrimKind::kPolygon: return "polygon";
    case PrimKind::kPatch: return "patch";
    case PrimKind::kFace: return "face";
  }
  return "?";
}

std::uint32_t Scene::NumUnified() const { return Ranges().begin[CR_NUM_PRIM_TYPES]; }

PrimRanges Scene::Ranges() const
{
  PrimRanges c{};
  uint n = 0;
  ForEachType([&](const auto& pieces, std::uint32_t k) {
    c.begin[k] = n;
    n += static_cast<uint>(pieces.size());
  });
  c.begin[CR_NUM_PRIM_TYPES] = n;
  return c;
}

std::uint32_t Scene::IdOfUnified(std::uint32_t g) const
{
  const PrimRanges r = Ranges();
  for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k)
    if (Prim_Is(&r, k, g)) return pieceIds[k][Prim_Local(&r, k, g)];
  throw std::out_of_range("unified primitive index past the scene's primitives");
}

std::uint32_t Scene::IdOfHit(std::uint32_t g, double u) const
{
  const PrimRanges r = Ranges();
  const std::uint32_t id = IdOfUnified(g);
  return Prim_Is(&r, CR_PRIM_CSG, g) ? id + static_cast<std::uint32_t>(u) : id;
}

std::vector<std::uint32_t> Scene::UnifiedIds() const
{
  std::vector<std::uint32_t> ids;
  ids.reserve(NumUnified());
  for (const auto& v : pieceIds) ids.insert(ids.end(), v.begin(), v.end());
  return ids;
}

namespace {
// b together with b translated by m: the box a piece sweeps over the
// shutter (a translation is linear in time, so its ends bound it), the
// moved corners rounded outward.
Bounds Swept(Bounds b, const glm::vec3& m)
{
  if (m == glm::vec3(0.0f) || b.Empty()) return b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = std::min(b.lo[a], FloatDown(double(b.lo[a]) + double(m[a])));
    b.hi[a] = std::max(b.hi[a], FloatUp(double(b.hi[a]) + double(m[a])));
  }
  return b;
}
}  // namespace

Bounds Scene::UnifiedBounds(std::uint32_t g) const
{
  const Bounds b = Visit(g, [](const auto& piece, std::uint32_t) { return FloatBounds(piece); });
  return hasMotion ? Swept(b, MotionOfUnified(g)) : b;
}

Bounds Scene::WorldBounds() const
{
  Bounds b;
  const PrimRanges r = Ranges();
  const std::uint32_t n = r.begin[CR_NUM_PRIM_TYPES];
  for (std::uint32_t g = 0; g < n; ++g) {
    const Bounds pb = Visit(r, g, [](const auto& piece, std::uint32_t) { return FloatBounds(piece); });
    b.Extend(hasMotion ? Swept(pb, MotionOfUnified(g)) : pb);
  }
  return b;
}

std::vector<float> Scene::UnifiedMotion() const
{
  if (!hasMotion) return {};
  const std::vector<std::uint32_t> ids = UnifiedIds();
  std::vector<float> m(4 * ids.size(), 0.0f);
  for (std::size_t g = 0; g < ids.size(); ++g)
    for (int a = 0; a < 3; ++a) m[4 * g + a] = prims[ids[g]].motion[a];
  return m;
}

std::uint32_t Scene::CountKind(PrimKind kind, std::uint32_t type) const
{
  return static_cast<std::uint32_t>(
      std::count_if(prims.begin(), prims.end(), [&](const PrimInfo& p) { return p.kind == kind && p.type == type; }));
}

namespace {

// Is the segment pq longer than 16 times its distance from the origin? The
// endpoints in a fixed order, so that pq and qp give the same answer.
bool LongEdge(const float* p, const float* q)
{
  glm::dvec3 a(p[0], p[1], p[2]), b(q[0], q[1], q[2]);
  if (b.x < a.x || (b.x == a.x && (b.y < a.y || (b.y == a.y && b.z < a.z)))) std::swap(a, b);
  const glm::dvec3 e = b - a;
  const double len2 = glm::dot(e, e);
  if (len2 == 0.0) return false;
  const double s = std::clamp(-glm::dot(a, e) / len2, 0.0, 1.0);
  const glm::dvec3 closest = a + s * e;
  return len2 > 256.0 * glm::dot(closest, closest);
}

}  // namespace

std::uint32_t TriangleEdgeFlags(const Triangle& t)
{
  return (LongEdge(t.v1, t.v2) ? CR_TRI_LONG_U : 0u) | (LongEdge(t.v2, t.v0) ? CR_TRI_LONG_V : 0u) |
         (LongEdge(t.v0, t.v1) ? CR_TRI_LONG_W : 0u);
}

bool AddPolygon(Scene& scene, PrimKind kind, const std::vector<glm::dvec3>& verts, const std::vector<glm::vec3>* normals,
                std::uint32_t material, std::uint32_t line, const std::string& file, bool warnIfDegenerate)
{
  PrimInfo info;
  info.kind = kind;
  info.type = CR_PRIM_TRIANGLE;
  info.material = material;
  info.line = line;
  info.firstPiece = static_cast<std::uint32_t>(scene.triangles.size());
  const auto id = static_cast<std::uint32_t>(scene.prims.size());

  Triangulation tri = TriangulatePolygon(verts);
  if (tri.degenerate) {
    if (warnIfDegenerate)
      Warn(fmt::format("{}:{}: degenerate {} ({} vertices, zero area): skipped, id {} kept", file, line, PrimInfoName(info),
                     verts.size(), id));
    scene.prims.push_back(info);
    return false;
  }
  if (tri.nonSimple)
    Warn(fmt::format("{}:{}: {} is not simple (self-intersecting?): triangulated as well as possible", file, line,
                     PrimInfoName(info)));
  if (normals && scene.triNormals.size() < scene.triangles.size()) scene.triNormals.resize(scene.triangles.size());
  for (const auto& t : tri.triangles) {
    Triangle piece{};
    for (int a = 0; a < 3; ++a) {
      piece.v0[a] = static_cast<float>(verts[t[0]][a]);
      piece.v1[a] = static_cast<float>(verts[t[1]][a]);
      piece.v2[a] = static_cast<float>(verts[t[2]][a]);
    }
    piece.flags = (verts.size() == 3 ? CR_TRI_REPORT_UV : 0u) | TriangleEdgeFlags(piece);
    scene.AddPiece(piece, id);
    if (normals) {
      scene.triNormals.push_back({(*normals)[t[0]], (*normals)[t[1]], (*normals)[t[2]]});
    } else if (!scene.triNormals.empty()) {
      scene.triNormals.push_back({glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)});
    }
  }
  info.nPieces = static_cast<std::uint32_t>(tri.triangles.size());
  scene.prims.push_back(info);
  return true;
}

Scene LoadScene(const std::string& path)
{
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".nff") return LoadNFF(path);
  if (ext == ".obj") return LoadOBJ(path);
  if (IsGeneratedName(path)) return LoadGenerated(path);
  throw InputError(path, 0, fmt::format("unknown scene format '{}' (expected .nff, .obj or gen:{}:N)", ext, GeneratedKinds()));
}

}  // namespace cr
