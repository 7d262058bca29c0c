// The scene model: camera, background, lights, materials and primitives, in
// the form every backend uploads (the per-type arrays of kernels/types.h).
//
// Primitive ids are those of ../shared/FORMATS.md: the 0-based position of a
// geometry statement in the file (NFF s/c/p/pp, OBJ f). A statement that is
// degenerate (a polygon of < 3 vertices or zero area, a sphere of radius 0)
// keeps its id but has no geometry. Polygons and patches are split into
// triangles ("pieces") that all report their statement's id.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "kernels/types.h"
#include "host/scene/area_light.h"

namespace cr {

struct Camera {
  glm::vec3 from{0.0f, 0.0f, 1.0f};
  glm::vec3 at{0.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float angle = 45.0f;  // degrees, between the centres of the outer pixel rows
  float hither = 0.0f;  // distance of the near plane along the view direction
  int width = 512;
  int height = 512;
  // Thin lens (NFF extension `lens aperture_radius focal_distance`, docs/FORMATS.md):
  // aperture 0 is the pinhole.
  float aperture = 0.0f;
  float focal = 1.0f;
};

struct Light {
  glm::vec3 position{0.0f};
  glm::vec3 color{1.0f};
};

// NFF `f`: colour, diffuse Kd, specular Ks, Phong exponent, transmittance T,
// index of refraction.
struct Material {
  glm::vec3 color{1.0f};
  float kd = 1.0f;
  float ks = 0.0f;
  float shine = 0.0f;
  float transmittance = 0.0f;
  float ior = 1.0f;
  glm::vec3 emission{0.0f};  // radiance emitted (an area light's, host/scene/area_light.h)
  int light = -1;            // index of its area light in Scene::areaLights, or -1
};

// What a geometry statement is: one piece of its primitive type (NFF `s`
// or `c`: a shape), or a polygon, patch or OBJ face split into triangles.
enum class PrimKind : std::uint8_t { kShape, kPolygon, kPatch, kFace };

// One geometry statement (one primitive id).
struct PrimInfo {
  PrimKind kind = PrimKind::kShape;
  std::uint8_t type = CR_PRIM_SPHERE;  // CR_PRIM_* of its pieces
  bool insideVisible = false;          // NFF negative radius
  std::uint32_t material = 0;
  std::uint32_t line = 0;        // line of the statement in its file
  std::uint32_t firstPiece = 0;  // index into the array of its type
  std::uint32_t nPieces = 0;     // 0: degenerate, no geometry
  // A part of its piece: a CSG solid's leaf statements share the solid's
  // one piece, leaf k with part k (its id is the piece's id + k); 0 for
  // every other statement.
  std::uint32_t part = 0;
  // NFF `motion dx dy dz` (docs/FORMATS.md): the statement's displacement
  // over the shutter interval; at ray time tau its pieces lie translated by
  // tau * motion. Zero for a static statement.
  glm::vec3 motion{0.0f};
};
// "sphere", "polygon", ...: the statement's kind, or its type for a shape.
const char* PrimInfoName(const PrimInfo& info);

// Selects a primitive type in overloads (Scene::Pieces and the per-type
// functions of host/prims/prim_host.h).
template <class T>
struct PrimTag {};

// Vertex normals of a patch piece (zero vectors for flat pieces).
using TriNormals = std::array<glm::vec3, 3>;

struct Bounds {
  glm::vec3 lo{INFINITY};
  glm::vec3 hi{-INFINITY};
  void Extend(const glm::vec3& p)
  {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void Extend(const Bounds& b)
  {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  bool Empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  glm::vec3 Extent() const { return hi - lo; }
};

struct Scene {
  std::string path;
  Camera camera;
  bool hasCamera = false;
  glm::vec3 background{0.0f};
  std::vector<Light> lights;
  std::vector<AreaLight> areaLights;  // NFF `la`, `ls` (each also one primitive id)
  std::vector<Material> materials;  // materials[0] is the default
  std::vector<PrimInfo> prims;      // indexed by primitive id

  // One array per primitive type (CR_PRIM_TYPES: spheres, triangles, ...),
  // Pieces(PrimTag<T>{}) names it generically and TypeIndex its CR_PRIM_*;
  // pieceIds[k][i]: primitive id of piece i of type k.
#define CR_SCENE_ARRAY_(T, U, a)                                           \
  std::vector<T> a;                                                        \
  std::vector<T>& Pieces(PrimTag<T>) { return a; }                         \
  const std::vector<T>& Pieces(PrimTag<T>) const { return a; }             \
  static constexpr std::uint32_t TypeIndex(PrimTag<T>) { return CR_PRIM_##U; }
  CR_PRIM_TYPES(CR_SCENE_ARRAY_)
#undef CR_SCENE_ARRAY_
  std::vector<std::uint32_t> pieceIds[CR_NUM_PRIM_TYPES];
  std::vector<TriNormals> triNormals;  // per triangle when any patch exists, else empty
  bool hasMotion = false;               // some statement moves (PrimInfo::motion != 0)

  // Appends a piece of primitive id `id`; returns its index in its array.
  template <class T>
  std::uint32_t AddPiece(const T& piece, std::uint32_t id)
  {
    auto& v = Pieces(PrimTag<T>{});
    v.push_back(piece);
    pieceIds[TypeIndex(PrimTag<T>{})].push_back(id);
    return static_cast<std::uint32_t>(v.size() - 1);
  }
  // f(piece, local) on unified piece g (its type's array, and its index
  // there). Loops over many pieces pass the scene's Ranges() computed once.
  template <class F>
  decltype(auto) Visit(std::uint32_t g, F&& f) const
  {
    return Visit(Ranges(), g, std::forward<F>(f));
  }
  template <class F>
  decltype(auto) Visit(const PrimRanges& r, std::uint32_t g, F&& f) const
  {
#define CR_SCENE_VISIT_(T, U, a) \
  if (g < Prim_End(&r, CR_PRIM_##U)) return f(a[Prim_Local(&r, CR_PRIM_##U, g)], Prim_Local(&r, CR_PRIM_##U, g));
    CR_PRIM_TYPES(CR_SCENE_VISIT_)
#undef CR_SCENE_VISIT_
    throw std::out_of_range("unified primitive index past the scene's primitives");
  }
  // f(array, k) on each type's array, in unified order.
  template <class F>
  void ForEachType(F&& f) const
  {
#define CR_SCENE_EACH_(T, U, a) f(a, CR_PRIM_##U);
    CR_PRIM_TYPES(CR_SCENE_EACH_)
#undef CR_SCENE_EACH_
  }

  std::uint32_t NumPrims() const { return static_cast<std::uint32_t>(prims.size()); }
  std::uint32_t NumUnified() const;
  PrimRanges Ranges() const;
  // Primitive id of unified index g (the types in CR_PRIM_TYPES order).
  std::uint32_t IdOfUnified(std::uint32_t g) const;
  // Primitive id of a hit on unified index g with its u (a CSG solid's
  // hit names its leaf by u, kernels/csg.h).
  std::uint32_t IdOfHit(std::uint32_t g, double u) const;
  // Scene-file id of every unified index, in order.
  std::vector<std::uint32_t> UnifiedIds() const;
  // Tight bounds of primitive g / of all geometry; for a moving piece, the
  // box it sweeps over the shutter interval (rounded outward).
  Bounds UnifiedBounds(std::uint32_t g) const;
  Bounds WorldBounds() const;
  // Statement counts by kind and type (tests assert them against the SPD table).
  std::uint32_t CountKind(PrimKind kind, std::uint32_t type) const;
  bool HasPatchNormals() const { return !triNormals.empty(); }
  // Motion of unified piece g (its statement's), and of every piece as the
  // kernels read it (kernels/motion.h: 4 floats per piece, dx dy dz 0);
  // empty for a static scene.
  glm::vec3 MotionOfUnified(std::uint32_t g) const { return hasMotion ? prims[IdOfUnified(g)].motion : glm::vec3(0.0f); }
  std::vector<float> UnifiedMotion() const;
  const Material& MaterialOf(std::uint32_t primId) const { return materials[prims[primId].material]; }
};

// Loads .nff, or .obj with an NFF-style .view file beside it (camera, lights,
// background). Throws InputError for malformed input.
Scene LoadScene(const std::string& path);
Scene LoadNFF(const std::string& path);
Scene LoadOBJ(const std::string& path);

// Parses an NFF text (used by LoadNFF and by tests on in-memory snippets).
// `name` is used in messages. With viewOnly, geometry statements are errors
// (an OBJ's .view file holds only v, b, l and comments).
void ParseNFF(std::string_view text, const std::string& name, Scene& scene, bool viewOnly = false);

// The CR_TRI_LONG_* bits of a triangle (kernels/types.h): its edges longer
// than 16 times their distance from the world origin. Robust mode checks the
// float edge functions of those edges against an error bound; the bits
// depend on each edge's two vertices only (in either order), so triangles
// sharing an edge agree. docs/TOLERANCE.md derives the factor.
std::uint32_t TriangleEdgeFlags(const Triangle& t);

// Adds a polygon (or patch, with normals) statement, triangulating it; used by
// the loaders. Returns false (after a warning) when it is degenerate.
bool AddPolygon(Scene& scene, PrimKind kind, const std::vector<glm::dvec3>& verts,
                const std::vector<glm::vec3>* normals, std::uint32_t material, std::uint32_t line,
                const std::string& file, bool warnIfDegenerate = true);

}  // namespace cr
