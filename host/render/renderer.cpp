#include "host/render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "host/core/error.h"
#include "host/rays/raygen.h"
#include "host/render/progress.h"
#include "host/scene/camera.h"
#include "host/scene/surface.h"

namespace cr {

void to_json(nlohmann::json& j, const RenderStats& s)
{
  j = nlohmann::json{{"eye_rays", s.eyeRays},
                     {"eye_hits", s.eyeHits},
                     {"reflection_rays", s.reflectionRays},
                     {"reflection_hits", s.reflectionHits},
                     {"refraction_rays", s.refractionRays},
                     {"refraction_hits", s.refractionHits},
                     {"shadow_rays", s.shadowRays},
                     {"shadow_hits", s.shadowHits},
                     {"total_internal_reflections", s.totalInternalReflections},
                     {"self_shadowed", s.selfShadowed},
                     {"trace_ms", s.traceMs},
                     {"shade_ms", s.shadeMs},
                     {"total_ms", s.totalMs}};
}

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

enum class RayType : std::uint8_t { Eye, Reflection, Refraction };

// A ray of the current bounce and what it carries back to its sample.
struct PathRay {
  RayRecord ray;
  glm::vec3 weight;
  std::uint32_t sample;
  std::uint8_t depth;
  RayType type;
};

// A shadow ray and the light it would deliver if unblocked.
struct ShadowRay {
  RayRecord ray;
  glm::vec3 light;
  std::uint32_t sample;
  std::uint32_t sourcePrim;
  std::uint8_t sourceOpaque;  // only opaque surfaces can be self-shadowed in error
  std::uint8_t valid;
};

RayRecord MakeRay(const glm::vec3& o, const glm::vec3& d, float tmax)
{
  RayRecord r;
  for (int a = 0; a < 3; ++a) {
    r.org[a] = o[a];
    r.dir[a] = d[a];
  }
  r.tmin = 0.0f;
  r.tmax = tmax;
  return r;
}

class Shader {
 public:
  Shader(const Scene& scene, const RenderOptions& opt) : scene_(scene), opt_(opt)
  {
    const double nl = double(std::max<std::size_t>(1, scene.lights.size()));
    intensity_ = float(std::sqrt(nl) / (2.0 * nl));
    twoSidedOpaque_ = opt.sides == Sides::Two || (opt.sides == Sides::Auto && scene.CountKind(PrimKind::kPatch, CR_PRIM_TRIANGLE) > 0);
  }

  // Shades one hit: returns the local colour (ambient, or background on a
  // miss) and fills up to nLights shadow rays and up to two spawned rays.
  glm::vec3 Shade(const PathRay& pr, const HitRecord& hit, ShadowRay* shadows, PathRay* spawned, int& nSpawned,
                  std::uint8_t& tir) const
  {
    nSpawned = 0;
    tir = 0;
    const std::size_t nl = scene_.lights.size();
    for (std::size_t l = 0; l < nl; ++l) shadows[l].valid = 0;
    if (hit.prim == CR_NO_HIT) return pr.weight * scene_.background;

    const std::uint32_t g = hit.prim;
    const std::uint32_t id = scene_.IdOfHit(g, hit.u);
    const PrimInfo& info = scene_.prims[id];
    const Material& m = scene_.materials[info.material];
    const glm::dvec3 o(pr.ray.org[0], pr.ray.org[1], pr.ray.org[2]);
    const glm::dvec3 dd(pr.ray.dir[0], pr.ray.dir[1], pr.ray.dir[2]);
    const SurfacePoint sp = SurfaceAt(scene_, g, o + double(hit.t) * dd, hit.u, hit.v);
    const glm::vec3 p = sp.p;
    const float offset = opt_.robustOffsets ? sp.robustError : sp.error;
    const glm::vec3 d = glm::normalize(glm::vec3(dd));
    glm::vec3 ng = sp.ng, ns = sp.ns;
    const glm::vec3 outward = ng;
    const bool transmitter = m.transmittance > 0.0f;
    // One-sided opaque surfaces keep their outward normal; two-sided ones
    // (transmitters, and every surface of a double-sided scene) face the ray.
    if ((transmitter || twoSidedOpaque_) && glm::dot(ng, d) > 0.0f) {
      ng = -ng;
      ns = -ns;
    }

    const glm::vec3 base = m.color * m.kd;
    glm::vec3 local = pr.weight * intensity_ * base;  // ambient

    // Direct light: one shadow ray per light the shading normal faces.
    for (std::size_t l = 0; l < nl; ++l) {
      const Light& light = scene_.lights[l];
      glm::vec3 L = light.position - p;
      const float dist = glm::length(L);
      if (!(dist > 0.0f)) continue;
      L /= dist;
      const float nDotL = glm::dot(ns, L);
      if (nDotL <= 0.0f) continue;
      glm::vec3 c = base * nDotL;
      if (m.ks > 0.0f) {
        glm::vec3 r = 2.0f * glm::dot(ns, L) * ns - L;
        float rv = std::max(0.0f, glm::dot(r, -d));
        c += glm::vec3(m.ks * std::pow(rv, m.shine));
      }
      const glm::vec3 side = glm::dot(ng, L) >= 0.0f ? ng : -ng;
      const glm::vec3 so = OffsetRayOrigin(p, offset, side);
      ShadowRay& s = shadows[l];
      s.ray = MakeRay(so, light.position - so, 1.0f);
      s.light = pr.weight * intensity_ * light.color * c;
      s.sample = pr.sample;
      s.sourcePrim = id;
      s.sourceOpaque = transmitter ? 0 : 1;
      s.valid = (s.ray.dir[0] != 0.0f || s.ray.dir[1] != 0.0f || s.ray.dir[2] != 0.0f) ? 1 : 0;
    }

    if (pr.depth >= opt_.maxDepth) return local;

    // Refraction (Snell) with total internal reflection.
    float kr = m.ks, kt = m.transmittance;
    glm::vec3 refrDir(0.0f);
    bool refract = false;
    if (transmitter) {
      float cosi = -glm::dot(d, outward);
      glm::vec3 n = outward;
      float eta = 1.0f / (m.ior > 0.0f ? m.ior : 1.0f);
      if (cosi < 0.0f) {  // leaving the medium
        cosi = -cosi;
        n = -outward;
        eta = 1.0f / eta;
      }
      const float k = 1.0f - eta * eta * (1.0f - cosi * cosi);
      if (k < 0.0f) {
        tir = 1;
        kr += kt;  // total internal reflection: the transmitted share reflects
      } else {
        refract = true;
        refrDir = glm::normalize(eta * d + (eta * cosi - std::sqrt(k)) * n);
        if (opt_.fresnel && !opt_.spd) {
          const float n1 = 1.0f, n2 = m.ior > 0.0f ? m.ior : 1.0f;
          const float r0 = ((n1 - n2) / (n1 + n2)) * ((n1 - n2) / (n1 + n2));
          const float c = eta > 1.0f ? std::sqrt(k) : cosi;  // the cosine on the optically thinner side
          const float f = r0 + (1.0f - r0) * std::pow(1.0f - c, 5.0f);
          kr = kr + kt * f;
          kt = kt * (1.0f - f);
        }
      }
    }
    // SPD: reflective *and transmitting* surfaces spawn reflection rays (the
    // SPD transmitters have Ks = 0); outside SPD mode a ray that can carry no
    // light is not cast.
    if (m.ks > 0.0f || transmitter) {
      if (!opt_.spd && kr <= 0.0f) goto refraction;
      glm::vec3 rd = d - 2.0f * glm::dot(d, ns) * ns;
      const glm::vec3 side = glm::dot(rd, ng) >= 0.0f ? ng : -ng;
      const glm::vec3 ro = OffsetRayOrigin(p, offset, side);
      spawned[nSpawned++] = PathRay{MakeRay(ro, rd, INFINITY), pr.weight * kr * glm::vec3(1.0f), pr.sample,
                                    std::uint8_t(pr.depth + 1), RayType::Reflection};
    }
  refraction:
    if (refract) {
      const glm::vec3 side = glm::dot(refrDir, ng) >= 0.0f ? ng : -ng;
      const glm::vec3 ro = OffsetRayOrigin(p, offset, side);
      spawned[nSpawned++] = PathRay{MakeRay(ro, refrDir, INFINITY), pr.weight * kt * m.color, pr.sample,
                                    std::uint8_t(pr.depth + 1), RayType::Refraction};
    }
    return local;
  }

 private:
  const Scene& scene_;
  const RenderOptions& opt_;
  float intensity_ = 1.0f;
  bool twoSidedOpaque_ = false;
};

}  // namespace

Image Render(const Scene& scene, Tracer& tracer, const RenderOptions& optIn, RenderStats* statsOut)
{
  RenderOptions opt = optIn;
  if (opt.spd) {
    opt.spp = 1;
    opt.maxDepth = 5;
    opt.fresnel = false;
  }
  if (opt.spp < 1 || opt.spp > 4096) throw InputError(fmt::format("--spp {} is not in 1..4096", opt.spp));
  if (opt.maxDepth < 1 || opt.maxDepth > 64) throw InputError(fmt::format("--depth {} is not in 1..64", opt.maxDepth));
  const int w = opt.width > 0 ? opt.width : scene.camera.width;
  const int h = opt.height > 0 ? opt.height : scene.camera.height;
  const CameraFrame frame = MakeCameraFrame(scene.camera, w, h);
  // Samples: SPD pixel corners, or spp stratified samples per pixel.
  const int cw = opt.spd ? w + 1 : w, ch = opt.spd ? h + 1 : h;
  const std::uint64_t perPixel = std::uint64_t(opt.spp);
  const std::uint64_t nSamples = std::uint64_t(cw) * std::uint64_t(ch) * perPixel;
  if (nSamples > (std::uint64_t(1) << 31)) throw InputError("render: too many samples (size x spp)");
  const int sx = std::max(1, int(std::ceil(std::sqrt(double(opt.spp)))));
  const int sy = (opt.spp + sx - 1) / sx;

  Shader shader(scene, opt);
  RenderStats st;
  std::vector<glm::vec3> accum(nSamples, glm::vec3(0.0f));
  const std::size_t nl = scene.lights.size();
  const std::uint64_t kChunk = std::uint64_t(1) << 18;
  Progress progress(nSamples, opt.progress);
  const auto t0 = Clock::now();

  std::vector<PathRay> queue, next;
  std::vector<HitRecord> hits;
  std::vector<ShadowRay> shadows;
  std::vector<PathRay> spawned;
  std::vector<int> nSpawned;
  std::vector<std::uint8_t> tirs;
  std::vector<glm::vec3> local;
  std::vector<RayRecord> batch;
  std::uint64_t raysCast = 0;

  for (std::uint64_t begin = 0; begin < nSamples; begin += kChunk) {
    const std::uint64_t end = std::min(nSamples, begin + kChunk);
    queue.resize(end - begin);
    tbb::parallel_for(begin, end, [&](std::uint64_t s) {
      const std::uint64_t pixel = s / perPixel, k = s % perPixel;
      const int x = int(pixel % std::uint64_t(cw)), y = int(pixel / std::uint64_t(cw));
      double px, py;
      if (opt.spd) {
        px = x - 0.5;
        py = y - 0.5;
      } else if (opt.spp == 1) {
        px = x;
        py = y;
      } else {
        const int kx = int(k) % sx, ky = int(k) / sx;
        px = x - 0.5 + (kx + ToUnit(HashRandom(opt.seed, 41, s))) / sx;
        py = y - 0.5 + (ky + ToUnit(HashRandom(opt.seed, 42, s))) / sy;
      }
      queue[s - begin] = PathRay{PrimaryRay(frame, px, py), glm::vec3(1.0f), std::uint32_t(s), 1, RayType::Eye};
    });
    while (!queue.empty()) {
      const std::size_t n = queue.size();
      batch.resize(n);
      for (std::size_t i = 0; i < n; ++i) batch[i] = queue[i].ray;
      auto ta = Clock::now();
      tracer.Trace(batch, hits, false, nullptr);
      auto tb = Clock::now();
      st.traceMs += Ms(ta, tb);
      raysCast += n;

      shadows.resize(n * nl);
      spawned.resize(n * 2);
      nSpawned.resize(n);
      tirs.resize(n);
      local.resize(n);
      tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        local[i] = shader.Shade(queue[i], hits[i], nl ? &shadows[i * nl] : nullptr, &spawned[i * 2], nSpawned[i], tirs[i]);
      });
      for (std::size_t i = 0; i < n; ++i) {
        accum[queue[i].sample] += local[i];
        st.totalInternalReflections += tirs[i];
        const bool hit = hits[i].prim != CR_NO_HIT;
        switch (queue[i].type) {
          case RayType::Eye: st.eyeRays++, st.eyeHits += hit; break;
          case RayType::Reflection: st.reflectionRays++, st.reflectionHits += hit; break;
          case RayType::Refraction: st.refractionRays++, st.refractionHits += hit; break;
        }
      }
      // Shadow rays of this bounce, compacted, then traced as one any-hit batch.
      std::size_t ns = 0;
      for (std::size_t i = 0; i < n * nl; ++i)
        if (shadows[i].valid) shadows[ns++] = shadows[i];
      shadows.resize(ns);
      auto tc = Clock::now();
      st.shadeMs += Ms(tb, tc);
      if (ns) {
        batch.resize(ns);
        for (std::size_t i = 0; i < ns; ++i) batch[i] = shadows[i].ray;
        tracer.Trace(batch, hits, true, nullptr);
        st.shadowRays += ns;
        raysCast += ns;
        for (std::size_t i = 0; i < ns; ++i) {
          if (hits[i].prim == CR_NO_HIT) {
            accum[shadows[i].sample] += shadows[i].light;
          } else {
            st.shadowHits++;
            if (shadows[i].sourceOpaque && scene.IdOfHit(hits[i].prim, hits[i].u) == shadows[i].sourcePrim) st.selfShadowed++;
          }
        }
      }
      st.traceMs += Ms(tc, Clock::now());
      next.clear();
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < nSpawned[i]; ++k) next.push_back(spawned[i * 2 + k]);
      std::swap(queue, next);
    }
    progress.Update(end, raysCast);
  }
  progress.Finish(raysCast);

  Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(std::size_t(w) * h * 3, 0.0f);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      glm::vec3 c(0.0f);
      if (opt.spd) {
        c = 0.25f * (accum[std::size_t(y) * cw + x] + accum[std::size_t(y) * cw + x + 1] +
                     accum[std::size_t(y + 1) * cw + x] + accum[std::size_t(y + 1) * cw + x + 1]);
      } else {
        const std::size_t p0 = (std::size_t(y) * w + x) * perPixel;
        for (std::uint64_t k = 0; k < perPixel; ++k) c += accum[p0 + k];
        c /= float(perPixel);
      }
      for (int a = 0; a < 3; ++a) img.rgb[(std::size_t(y) * w + x) * 3 + a] = c[a];
    }
  });
  st.totalMs = Ms(t0, Clock::now());
  if (statsOut) *statsOut = st;
  return img;
}

}  // namespace cr
