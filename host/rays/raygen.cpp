#include "host/rays/raygen.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "host/core/error.h"
#include "host/scene/camera.h"
#include "host/scene/surface.h"

namespace cr {

RayKind ParseRayKind(const std::string& s)
{
  if (s == "primary") return RayKind::Primary;
  if (s == "shadow") return RayKind::Shadow;
  if (s == "diffuse") return RayKind::Diffuse;
  if (s == "random") return RayKind::Random;
  if (s == "soft") return RayKind::Soft;
  if (s == "path") return RayKind::Path;
  throw InputError(fmt::format("unknown ray kind '{}' (expected primary, shadow, diffuse, random, soft or path)", s));
}

const char* RayKindName(RayKind k)
{
  switch (k) {
    case RayKind::Primary: return "primary";
    case RayKind::Shadow: return "shadow";
    case RayKind::Diffuse: return "diffuse";
    case RayKind::Random: return "random";
    case RayKind::Soft: return "soft";
    case RayKind::Path: return "path";
  }
  return "?";
}

std::uint64_t HashRandom(std::uint64_t seed, std::uint64_t stream, std::uint64_t index)
{
  // splitmix64 finaliser over a mix of the three inputs.
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + stream * 0xD1B54A32D192ED03ull + index * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

namespace {

glm::vec3 ToF(const glm::dvec3& v) { return glm::vec3(v); }

// A cosine-weighted direction about ng (Malley's method).
glm::dvec3 CosineAbout(const glm::dvec3& ng, std::uint64_t seed, std::uint64_t stream, std::uint64_t sample)
{
  double u1 = ToUnit(HashRandom(seed, stream, 2 * sample)), u2 = ToUnit(HashRandom(seed, stream, 2 * sample + 1));
  double rad = std::sqrt(u1), phi = 2.0 * 3.14159265358979323846 * u2;
  glm::dvec3 a = std::fabs(ng.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  glm::dvec3 t1 = glm::normalize(glm::cross(ng, a)), t2 = glm::cross(ng, t1);
  return glm::normalize(rad * std::cos(phi) * t1 + rad * std::sin(phi) * t2 + std::sqrt(std::max(0.0, 1.0 - u1)) * ng);
}

// The area lights soft-shadow rays aim at: the scene's, or spheres around
// its point lights.
std::vector<AreaLight> SoftLights(const Scene& scene)
{
  if (!scene.areaLights.empty() || scene.lights.empty()) return scene.areaLights;
  const Bounds b = scene.WorldBounds();
  const double radius = b.Empty() ? 1.0 : 0.01 * glm::length(glm::dvec3(b.hi) - glm::dvec3(b.lo));
  std::vector<AreaLight> out;
  for (const Light& l : scene.lights) out.push_back(SphereLight(glm::dvec3(l.position), radius, l.color));
  return out;
}

// Secondary rays of one primary sample.
// `time`: the sample's time in the shutter interval (0 for a static scene).
void Secondary(const Scene& scene, const ref::ReferenceTracer& tr, RayKind kind, const RayRecord& primary, float time,
               std::uint64_t seed, std::uint64_t sample, const std::vector<AreaLight>& soft, std::vector<RayRecord>& out)
{
  ref::DRay r = ref::MakeRay(primary);
  r.time = time;
  ref::RefHit h = tr.Intersect(r);
  if (!h.Found()) return;
  const SurfacePoint sp = SurfaceAt(scene, h.g, r.o + h.t * r.d, h.u, h.v, time);
  glm::dvec3 ng(sp.ng), ns(sp.ns);
  if (glm::dot(ng, r.d) > 0.0) ng = -ng;  // face the viewer
  if (glm::dot(ns, r.d) > 0.0) ns = -ns;
  const glm::dvec3 p(sp.p);
  if (kind == RayKind::Shadow) {
    for (const Light& l : scene.lights) {
      glm::dvec3 L = glm::dvec3(l.position) - p;
      if (glm::dot(ns, L) <= 0.0) continue;
      glm::dvec3 side = glm::dot(ng, L) >= 0.0 ? ng : -ng;
      glm::vec3 o = OffsetRayOrigin(sp.p, sp.error, ToF(side));
      glm::vec3 d = l.position - o;
      if (d == glm::vec3(0.0f)) continue;
      out.push_back(MakeRay(o, d, 1.0f));
    }
  } else if (kind == RayKind::Soft) {
    for (std::size_t l = 0; l < soft.size(); ++l) {
      const LightSample ls = SampleAreaLight(soft[l], p, ToUnit(HashRandom(seed, 12 + 2 * l, sample)),
                                             ToUnit(HashRandom(seed, 13 + 2 * l, sample)));
      if (!(ls.pdf > 0.0) || glm::dot(ns, ls.p - p) <= 0.0) continue;
      const glm::vec3 side = ToF(glm::dot(ng, ls.p - p) >= 0.0 ? ng : -ng);
      const RayRecord sr = ShadowRayToLight(sp.p, sp.error, side, soft[l], ls);
      if (sr.dir[0] != 0.0f || sr.dir[1] != 0.0f || sr.dir[2] != 0.0f) out.push_back(sr);
    }
  } else {
    glm::vec3 df = ToF(CosineAbout(ng, seed, 11, sample));
    if (df == glm::vec3(0.0f)) return;
    RayRecord dr = MakeRay(OffsetRayOrigin(sp.p, sp.error, ToF(ng)), df, INFINITY);
    if (kind == RayKind::Path) {
      // Follow it to its hit and bounce once more.
      ref::DRay r2 = ref::MakeRay(dr);
      r2.time = time;
      ref::RefHit h2 = tr.Intersect(r2);
      if (!h2.Found()) return;
      const SurfacePoint s2 = SurfaceAt(scene, h2.g, r2.o + h2.t * r2.d, h2.u, h2.v, time);
      glm::dvec3 n2(s2.ng);
      if (glm::dot(n2, r2.d) > 0.0) n2 = -n2;
      df = ToF(CosineAbout(n2, seed, 14, sample));
      if (df == glm::vec3(0.0f)) return;
      dr = MakeRay(OffsetRayOrigin(s2.p, s2.error, ToF(n2)), df, INFINITY);
    }
    out.push_back(dr);
  }
}

}  // namespace

std::vector<RayRecord> GenerateRays(const Scene& scene, const ref::ReferenceTracer& tr, const RayGenOptions& opt,
                                    std::vector<float>* times)
{
  // A sample's time: uniform in the shutter for a scene with motion (and
  // times wanted), else 0.
  const bool timed = times && scene.hasMotion;
  if (times) times->clear();
  auto timeOf = [&](std::uint64_t sample) { return timed ? float(ToUnit(HashRandom(opt.seed, 41, sample))) : 0.0f; };
  const int w = opt.width > 0 ? opt.width : scene.camera.width;
  const int h = opt.height > 0 ? opt.height : scene.camera.height;
  const CameraFrame frame = MakeCameraFrame(scene.camera, w, h);
  const std::uint64_t target = opt.count ? opt.count : std::uint64_t(w) * std::uint64_t(h);
  // 2^27 rays are 4 GiB of records: beyond that, ask for smaller sets.
  constexpr std::uint64_t kMaxRays = std::uint64_t(1) << 27;
  const std::uint64_t primaries = std::uint64_t(opt.spdCorners ? w + 1 : w) * std::uint64_t(opt.spdCorners ? h + 1 : h);
  if (target > kMaxRays || primaries > kMaxRays)
    throw InputError(fmt::format("{} x {} image / {} rays: more than {} rays per set; use a smaller --size or --count",
                                 w, h, target, kMaxRays));
  std::vector<RayRecord> rays;

  if (opt.kind == RayKind::Primary) {
    const int nx = opt.spdCorners ? w + 1 : w, ny = opt.spdCorners ? h + 1 : h;
    const double off = opt.spdCorners ? -0.5 : 0.0;
    rays.resize(std::size_t(nx) * std::size_t(ny));
    tbb::parallel_for(0, ny, [&](int y) {
      for (int x = 0; x < nx; ++x) rays[std::size_t(y) * nx + x] = PrimaryRay(frame, x + off, y + off);
    });
    if (timed)
      for (std::size_t i = 0; i < rays.size(); ++i) times->push_back(timeOf(i));
    return rays;
  }
  if (opt.kind == RayKind::Random) {
    Bounds b = scene.WorldBounds();
    rays.resize(target);
    tbb::parallel_for(std::uint64_t(0), target, [&](std::uint64_t i) {
      glm::vec3 o;
      for (int a = 0; a < 3; ++a)
        o[a] = static_cast<float>(b.lo[a] + (double(b.hi[a]) - b.lo[a]) * ToUnit(HashRandom(opt.seed, 21 + a, i)));
      double z = 1.0 - 2.0 * ToUnit(HashRandom(opt.seed, 24, i));
      double phi = 2.0 * 3.14159265358979323846 * ToUnit(HashRandom(opt.seed, 25, i));
      double s = std::sqrt(std::max(0.0, 1.0 - z * z));
      glm::vec3 d(static_cast<float>(s * std::cos(phi)), static_cast<float>(s * std::sin(phi)), static_cast<float>(z));
      if (d == glm::vec3(0.0f)) d = glm::vec3(0.0f, 0.0f, 1.0f);
      rays[i] = MakeRay(o, d, INFINITY);
    });
    if (timed)
      for (std::size_t i = 0; i < rays.size(); ++i) times->push_back(timeOf(i));
    return rays;
  }

  // Shadow rays aim at the point lights: a scene lit only by emitting
  // surfaces has none to aim at (its soft-shadow rays aim at those).
  if (opt.kind == RayKind::Shadow && scene.lights.empty())
    throw InputError(scene.path, 0,
                     "no shadow rays: the scene has no point light (an `l` statement); its emitting surfaces, if "
                     "any, take soft-shadow rays (--kind soft)");
  // Shadow and diffuse: passes of primary samples (pixel centres, then
  // jittered) until enough rays exist.
  const std::uint64_t perPass = std::uint64_t(w) * std::uint64_t(h);
  const std::vector<AreaLight> soft = opt.kind == RayKind::Soft ? SoftLights(scene) : std::vector<AreaLight>{};
  for (int pass = 0; pass < 64 && rays.size() < target; ++pass) {
    std::vector<std::vector<RayRecord>> perRow(static_cast<std::size_t>(h));
    std::vector<std::vector<float>> rowTimes(static_cast<std::size_t>(h));
    tbb::parallel_for(0, h, [&](int y) {
      auto& row = perRow[static_cast<std::size_t>(y)];
      for (int x = 0; x < w; ++x) {
        const std::uint64_t sample = std::uint64_t(pass) * perPass + std::uint64_t(y) * w + x;
        double jx = pass ? ToUnit(HashRandom(opt.seed, 31, sample)) - 0.5 : 0.0;
        double jy = pass ? ToUnit(HashRandom(opt.seed, 32, sample)) - 0.5 : 0.0;
        const float time = timeOf(sample);
        Secondary(scene, tr, opt.kind, PrimaryRay(frame, x + jx, y + jy), time, opt.seed, sample, soft, row);
        if (timed) rowTimes[static_cast<std::size_t>(y)].resize(row.size(), time);
      }
    });
    for (auto& row : perRow) rays.insert(rays.end(), row.begin(), row.end());
    if (timed)
      for (auto& t : rowTimes) times->insert(times->end(), t.begin(), t.end());
  }
  if (rays.empty())
    throw InputError(scene.path, 0,
                     fmt::format("no {} rays: no primary ray hits anything{}", RayKindName(opt.kind),
                                 IsOcclusionKind(opt.kind) ? " that faces a light" : ""));
  if (rays.size() < target)
    Warn(fmt::format("{}: only {} {} rays after 64 passes (asked for {})", scene.path, rays.size(),
                     RayKindName(opt.kind), target));
  if (rays.size() > target) rays.resize(target);
  if (timed) times->resize(rays.size());
  return rays;
}

}  // namespace cr
