#include "host/scene/scene.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/scene/triangulate.h"

namespace cr {

const char* PrimKindName(PrimKind kind)
{
  switch (kind) {
    case PrimKind::kSphere: return "sphere";
    case PrimKind::kCone: return "cone";
    case PrimKind::kPolygon: return "polygon";
    case PrimKind::kPatch: return "patch";
    case PrimKind::kFace: return "face";
  }
  return "?";
}

std::uint32_t Scene::NumUnified() const
{
  return static_cast<std::uint32_t>(spheres.size() + triangles.size() + cones.size());
}

PrimRanges Scene::Ranges() const
{
  PrimRanges c{};
  c.begin[CR_PRIM_SPHERE] = 0u;
  c.begin[CR_PRIM_TRIANGLE] = static_cast<uint>(spheres.size());
  c.begin[CR_PRIM_CONE] = c.begin[CR_PRIM_TRIANGLE] + static_cast<uint>(triangles.size());
  c.begin[CR_NUM_PRIM_TYPES] = c.begin[CR_PRIM_CONE] + static_cast<uint>(cones.size());
  return c;
}

std::uint32_t Scene::IdOfUnified(std::uint32_t g) const
{
  const auto nS = static_cast<std::uint32_t>(spheres.size());
  const auto nT = static_cast<std::uint32_t>(triangles.size());
  if (g < nS) return sphereIds[g];
  if (g < nS + nT) return triangleIds[g - nS];
  return coneIds[g - nS - nT];
}

std::vector<std::uint32_t> Scene::UnifiedIds() const
{
  std::vector<std::uint32_t> ids;
  ids.reserve(NumUnified());
  ids.insert(ids.end(), sphereIds.begin(), sphereIds.end());
  ids.insert(ids.end(), triangleIds.begin(), triangleIds.end());
  ids.insert(ids.end(), coneIds.begin(), coneIds.end());
  return ids;
}

static glm::vec3 V3(const float* p) { return {p[0], p[1], p[2]}; }

Bounds Scene::UnifiedBounds(std::uint32_t g) const
{
  Bounds b;
  const auto nS = static_cast<std::uint32_t>(spheres.size());
  const auto nT = static_cast<std::uint32_t>(triangles.size());
  if (g < nS) {
    const Sphere& s = spheres[g];
    glm::vec3 c = V3(s.center);
    // Outward rounding: c +- r may round inward by half an ulp.
    glm::vec3 r(s.radius);
    b.lo = glm::vec3(std::nextafter(c.x - r.x, -INFINITY), std::nextafter(c.y - r.y, -INFINITY),
                     std::nextafter(c.z - r.z, -INFINITY));
    b.hi = glm::vec3(std::nextafter(c.x + r.x, INFINITY), std::nextafter(c.y + r.y, INFINITY),
                     std::nextafter(c.z + r.z, INFINITY));
  } else if (g < nS + nT) {
    const Triangle& t = triangles[g - nS];
    b.Extend(V3(t.v0));
    b.Extend(V3(t.v1));
    b.Extend(V3(t.v2));
  } else {
    // A cone lies inside the box of its two end discs; a disc of radius r
    // normal to unit axis w extends r * sqrt(1 - w_i^2) along axis i.
    const Cone& c = cones[g - nS - nT];
    glm::dvec3 p0(c.base[0], c.base[1], c.base[2]), p1(c.apex[0], c.apex[1], c.apex[2]);
    glm::dvec3 w = glm::normalize(p1 - p0);
    glm::dvec3 e = glm::sqrt(glm::max(glm::dvec3(1.0) - w * w, glm::dvec3(0.0)));
    glm::dvec3 lo = glm::min(p0 - e * double(c.baseRadius), p1 - e * double(c.apexRadius));
    glm::dvec3 hi = glm::max(p0 + e * double(c.baseRadius), p1 + e * double(c.apexRadius));
    // Pad by a relative epsilon and round outward to float.
    glm::dvec3 pad = (hi - lo) * 1e-6 + glm::abs(lo) * 1e-7 + glm::abs(hi) * 1e-7;
    lo -= pad;
    hi += pad;
    b.lo = glm::vec3(lo);
    b.hi = glm::vec3(hi);
    for (int a = 0; a < 3; ++a) {
      if (double(b.lo[a]) > lo[a]) b.lo[a] = std::nextafter(b.lo[a], -INFINITY);
      if (double(b.hi[a]) < hi[a]) b.hi[a] = std::nextafter(b.hi[a], INFINITY);
    }
  }
  return b;
}

Bounds Scene::WorldBounds() const
{
  Bounds b;
  const std::uint32_t n = NumUnified();
  for (std::uint32_t g = 0; g < n; ++g) b.Extend(UnifiedBounds(g));
  return b;
}

std::uint32_t Scene::CountKind(PrimKind kind) const
{
  return static_cast<std::uint32_t>(std::count_if(prims.begin(), prims.end(), [&](const PrimInfo& p) { return p.kind == kind; }));
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
  info.material = material;
  info.line = line;
  info.firstPiece = static_cast<std::uint32_t>(scene.triangles.size());
  const auto id = static_cast<std::uint32_t>(scene.prims.size());

  Triangulation tri = TriangulatePolygon(verts);
  if (tri.degenerate) {
    if (warnIfDegenerate)
      Warn(fmt::format("{}:{}: degenerate {} ({} vertices, zero area): skipped, id {} kept", file, line, PrimKindName(kind),
                     verts.size(), id));
    scene.prims.push_back(info);
    return false;
  }
  if (tri.nonSimple)
    Warn(fmt::format("{}:{}: {} is not simple (self-intersecting?): triangulated as well as possible", file, line,
                     PrimKindName(kind)));
  if (normals && scene.triNormals.size() < scene.triangles.size()) scene.triNormals.resize(scene.triangles.size());
  for (const auto& t : tri.triangles) {
    Triangle piece{};
    for (int a = 0; a < 3; ++a) {
      piece.v0[a] = static_cast<float>(verts[t[0]][a]);
      piece.v1[a] = static_cast<float>(verts[t[1]][a]);
      piece.v2[a] = static_cast<float>(verts[t[2]][a]);
    }
    piece.flags = (verts.size() == 3 ? CR_TRI_REPORT_UV : 0u) | TriangleEdgeFlags(piece);
    scene.triangles.push_back(piece);
    scene.triangleIds.push_back(id);
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
  throw InputError(path, 0, fmt::format("unknown scene format '{}' (expected .nff or .obj)", ext));
}

}  // namespace cr
