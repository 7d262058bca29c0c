// The Whitted integrator (renderer.h): Phong shading from point lights with
// shadow rays and reflection/refraction trees, exactly as the SPD procedure
// has it; area lights sampled over their area, emitters seen by eye,
// reflected and refracted rays, and the first hit's diffuse gather (--diffuse).
#include <algorithm>
#include <chrono>
#include <cmath>

#include <tbb/parallel_for.h>

#include "host/render/bsdf.h"
#include "host/render/integrator.h"
#include "host/render/sampling.h"
#include "host/scene/surface.h"

namespace cr {

namespace {


enum class RayType : std::uint8_t { Eye, Reflection, Refraction, Diffuse };

// A ray of the current bounce and what it carries back to its sample; node
// numbers the ray in its sample's tree (the streams of its random numbers).
struct PathRay {
  RayRecord ray;
  glm::vec3 weight;
  std::uint32_t point;  // index in the chunk
  std::uint8_t depth;
  RayType type;
  std::uint64_t node;
};


// Random-number streams (RenderContext::Random): per tree node, 64 apart.
constexpr std::uint64_t kLightStream = 100;    // + 4 l: area light l's point
constexpr std::uint64_t kDiffuseStream = 1 << 20;  // + 2 j: gather ray j

class Shader {
 public:
  Shader(const RenderContext& ctx, int k, std::uint64_t begin) : ctx_(ctx), scene_(ctx.scene), opt_(ctx.opt), k_(k), begin_(begin)
  {
    ambient_ = scene_.areaLights.empty() && opt_.diffuse.kind == DiffuseGather::Kind::None;
  }

  // Shades one hit: returns the local colour (ambient and emission, or the
  // background on a miss) and fills the shadow rays (one per point light,
  // then one per area light) and the spawned rays.
  glm::vec3 Shade(const PathRay& pr, const HitRecord& hit, ShadowRay* shadows, PathRay* spawned, int& nSpawned,
                  std::uint8_t& tir) const
  {
    nSpawned = 0;
    tir = 0;
    const std::size_t nl = scene_.lights.size(), na = scene_.areaLights.size();
    for (std::size_t l = 0; l < nl + na; ++l) shadows[l].valid = 0;
    if (hit.prim == CR_NO_HIT) return pr.weight * scene_.background;

    const std::uint32_t g = hit.prim;
    const std::uint32_t id = scene_.IdOfHit(g, hit.u);
    const PrimInfo& info = scene_.prims[id];
    const Material& m = scene_.materials[info.material];
    const glm::dvec3 o(pr.ray.org[0], pr.ray.org[1], pr.ray.org[2]);
    const glm::dvec3 dd(pr.ray.dir[0], pr.ray.dir[1], pr.ray.dir[2]);
    const SurfacePoint sp = SurfaceAt(scene_, g, o + double(hit.t) * dd, hit.u, hit.v, ctx_.Time(begin_ + pr.point, k_));
    const glm::vec3 p = sp.p;
    const float offset = opt_.robustOffsets ? sp.robustError : sp.error;
    const glm::vec3 d = glm::normalize(glm::vec3(dd));
    glm::vec3 ng = sp.ng, ns = sp.ns;
    const glm::vec3 outward = ng;
    const bool transmitter = m.transmittance > 0.0f;
    // One-sided opaque surfaces keep their outward normal; two-sided ones
    // (transmitters, and every surface of a double-sided scene) face the ray.
    const bool facing = transmitter || ctx_.twoSidedOpaque;
    if (facing && glm::dot(ng, d) > 0.0f) {
      ng = -ng;
      ns = -ns;
    }

    const glm::vec3 base = m.color * m.kd;
    glm::vec3 local = ambient_ ? pr.weight * ctx_.intensity * base : glm::vec3(0.0f);
    // An emitter seen directly or in a mirror (a gather ray's light is the
    // first hit's direct light, sampled there).
    if (m.light >= 0 && pr.type != RayType::Diffuse)
      local += pr.weight * AreaLightEmission(scene_.areaLights[std::size_t(m.light)], dd);

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
      s.light = pr.weight * ctx_.intensity * light.color * c;
      s.point = pr.point;
      s.sourcePrim = id;
      s.sourceOpaque = transmitter ? 0 : 1;
      s.valid = (s.ray.dir[0] != 0.0f || s.ray.dir[1] != 0.0f || s.ray.dir[2] != 0.0f) ? 1 : 0;
    }

    // Area lights: a point on each, stratified over the pixel's samples at
    // the first hit; the diffuse part Kd colour / pi of the surface (its
    // specular part sees the lights through its mirror rays).
    const bool front = facing || !(glm::dot(outward, d) > 0.0f);
    const std::uint64_t sample = ctx_.Sample(begin_ + pr.point, k_);
    if (na && m.kd > 0.0f && front) {
      for (std::size_t l = 0; l < na; ++l) {
        const AreaLight& light = scene_.areaLights[l];
        const std::uint64_t stream = pr.node * 64 + kLightStream + 4 * l;
        const glm::dvec2 u = pr.node == 1 ? ctx_.Stratified(begin_ + pr.point, k_, stream)
                                          : glm::dvec2(ctx_.Random(sample, stream), ctx_.Random(sample, stream + 2));
        const LightSample ls = SampleAreaLight(light, glm::dvec3(p), u.x, u.y);
        if (!(ls.pdf > 0.0)) continue;
        const glm::dvec3 wi = glm::normalize(ls.p - glm::dvec3(p));
        const double cosS = glm::dot(glm::dvec3(ns), wi);
        if (!(cosS > 0.0)) continue;
        const glm::vec3 side = glm::dot(glm::dvec3(ng), wi) >= 0.0 ? ng : -ng;
        ShadowRay& s = shadows[nl + l];
        s.ray = ShadowRayToLight(p, offset, side, light, ls);
        s.light = pr.weight * base * ls.radiance * float(cosS / (kPi * ls.pdf));
        s.point = pr.point;
        s.sourcePrim = id;
        s.sourceOpaque = transmitter ? 0 : 1;
        s.valid = 1;
      }
    }

    if (pr.depth >= opt_.maxDepth) return local;
    GatherDiffuse(pr, m, p, offset, ng, ns, front, sample, spawned, nSpawned);

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
      const float kk = 1.0f - eta * eta * (1.0f - cosi * cosi);
      if (kk < 0.0f) {
        tir = 1;
        kr += kt;  // total internal reflection: the transmitted share reflects
      } else {
        refract = true;
        refrDir = glm::normalize(eta * d + (eta * cosi - std::sqrt(kk)) * n);
        if (opt_.fresnel && !opt_.spd) {
          const float n1 = 1.0f, n2 = m.ior > 0.0f ? m.ior : 1.0f;
          const float r0 = ((n1 - n2) / (n1 + n2)) * ((n1 - n2) / (n1 + n2));
          const float c = eta > 1.0f ? std::sqrt(kk) : cosi;  // the cosine on the optically thinner side
          const float f = r0 + (1.0f - r0) * std::pow(1.0f - c, 5.0f);
          kr = kr + kt * f;
          kt = kt * (1.0f - f);
        }
      }
    }
    // SPD: reflective *and transmitting* surfaces spawn reflection rays (the
    // SPD transmitters have Ks = 0); outside SPD mode a ray that can carry no
    // light is not cast.
    if ((m.ks > 0.0f || transmitter) && (opt_.spd || kr > 0.0f)) {
      glm::vec3 rd = d - 2.0f * glm::dot(d, ns) * ns;
      const glm::vec3 side = glm::dot(rd, ng) >= 0.0f ? ng : -ng;
      const glm::vec3 ro = OffsetRayOrigin(p, offset, side);
      spawned[nSpawned++] = PathRay{MakeRay(ro, rd, INFINITY), pr.weight * kr * glm::vec3(1.0f), pr.point,
                                    std::uint8_t(pr.depth + 1), RayType::Reflection, pr.node * 3 + 1};
    }
    if (refract) {
      const glm::vec3 side = glm::dot(refrDir, ng) >= 0.0f ? ng : -ng;
      const glm::vec3 ro = OffsetRayOrigin(p, offset, side);
      spawned[nSpawned++] = PathRay{MakeRay(ro, refrDir, INFINITY), pr.weight * kt * m.color, pr.point,
                                    std::uint8_t(pr.depth + 1), RayType::Refraction, pr.node * 3 + 2};
    }
    return local;
  }

 private:
  // --diffuse at the eye ray's hit: the gather rays, each of weight
  // (Kd colour / pi) cos(theta) d(omega) / pdf.
  void GatherDiffuse(const PathRay& pr, const Material& m, const glm::vec3& p, float offset, const glm::vec3& ng,
                     const glm::vec3& ns, bool front, std::uint64_t sample, PathRay* spawned, int& nSpawned) const
  {
    const DiffuseGather& dg = opt_.diffuse;
    if (dg.kind == DiffuseGather::Kind::None || pr.type != RayType::Eye || !(m.kd > 0.0f) || !front) return;
    const glm::dvec3 n(ns);
    const glm::vec3 base = pr.weight * m.color * m.kd;
    auto spawn = [&](const glm::dvec3& dir, const glm::vec3& weight, int j) {
      const glm::vec3 side = glm::dot(glm::dvec3(ng), dir) >= 0.0 ? ng : -ng;
      spawned[nSpawned++] = PathRay{MakeRay(OffsetRayOrigin(p, offset, side), glm::vec3(dir), INFINITY), weight, pr.point,
                                    std::uint8_t(pr.depth + 1), RayType::Diffuse, kDiffuseStream + std::uint64_t(j)};
    };
    if (dg.kind == DiffuseGather::Kind::Cosine) {
      const float share = 1.0f / float(dg.n);
      for (int j = 0; j < dg.n; ++j) {
        const std::uint64_t stream = kDiffuseStream + 4 * std::uint64_t(j);
        const glm::dvec3 dir = CosineDirection(n, ctx_.Random(sample, stream), ctx_.Random(sample, stream + 2));
        if (glm::dot(dir, n) > 0.0) spawn(dir, base * share, j);
      }
      return;
    }
    // The cube [-1, 1]^3 around p, face by face, cell by cell: a point x
    // uniform in the cell sees direction x / |x| with density
    // |x|^3 / cell area in solid angle.
    const int N = dg.n;
    const double cell = 2.0 / N, area = cell * cell;
    int j = 0;
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2;
      const double sign = face % 2 ? -1.0 : 1.0;
      for (int a = 0; a < N; ++a)
        for (int b = 0; b < N; ++b, ++j) {
          const std::uint64_t stream = kDiffuseStream + 4 * std::uint64_t(j);
          const double s = -1.0 + (a + ctx_.Random(sample, stream)) * cell;
          const double t = -1.0 + (b + ctx_.Random(sample, stream + 2)) * cell;
          glm::dvec3 x;
          x[axis] = sign;
          x[(axis + 1) % 3] = s;
          x[(axis + 2) % 3] = t;
          const double r = glm::length(x);
          const glm::dvec3 dir = x / r;
          const double cosT = glm::dot(dir, n);
          if (!(cosT > 0.0)) continue;
          spawn(dir, base * float(cosT * area / (kPi * r * r * r)), j);
        }
    }
  }

  const RenderContext& ctx_;
  const Scene& scene_;
  const RenderOptions& opt_;
  int k_;
  std::uint64_t begin_;
  bool ambient_ = true;
};

}  // namespace

void WhittedChunk(const RenderContext& ctx, Tracer& tracer, std::uint64_t begin, std::uint64_t end, int k,
                  glm::vec3* out, RenderStats& st, std::uint64_t& raysCast)
{
  const Scene& scene = ctx.scene;
  const std::size_t nl = scene.lights.size() + scene.areaLights.size();
  const std::size_t gather = 2 + std::size_t(ctx.opt.diffuse.Rays());
  Shader shader(ctx, k, begin);
  std::vector<PathRay> queue(end - begin), next;
  std::vector<HitRecord> hits;
  std::vector<ShadowRay> shadows;
  std::vector<PathRay> spawned;
  std::vector<int> nSpawned;
  std::vector<std::uint8_t> tirs;
  std::vector<glm::vec3> local;
  std::vector<RayRecord> batch;
  tbb::parallel_for(begin, end, [&](std::uint64_t pt) {
    queue[pt - begin] = PathRay{ctx.CameraRay(pt, k), glm::vec3(1.0f), std::uint32_t(pt - begin), 1, RayType::Eye, 1};
  });
  while (!queue.empty()) {
    const std::size_t n = queue.size();
    // Only the eye rays (the first queue) gather: room for their rays.
    const std::size_t maxSpawn = queue[0].type == RayType::Eye ? gather : 2;
    TraceQueue(ctx, begin, k, tracer, queue, batch, hits, st, raysCast);
    const auto tb = std::chrono::steady_clock::now();
    shadows.resize(n * nl);
    spawned.resize(n * maxSpawn);
    nSpawned.resize(n);
    tirs.resize(n);
    local.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      local[i] = shader.Shade(queue[i], hits[i], nl ? &shadows[i * nl] : nullptr, &spawned[i * maxSpawn], nSpawned[i],
                              tirs[i]);
    });
    for (std::size_t i = 0; i < n; ++i) {
      out[queue[i].point] += local[i];
      st.totalInternalReflections += tirs[i];
      const bool hit = hits[i].prim != CR_NO_HIT;
      switch (queue[i].type) {
        case RayType::Eye: st.eyeRays++, st.eyeHits += hit; break;
        case RayType::Reflection: st.reflectionRays++, st.reflectionHits += hit; break;
        case RayType::Refraction: st.refractionRays++, st.refractionHits += hit; break;
        case RayType::Diffuse: st.diffuseRays++, st.diffuseHits += hit; break;
      }
    }
    st.shadeMs += MsSince(tb);
    // Shadow rays of this bounce, traced as one any-hit batch.
    TraceShadows(ctx, begin, k, tracer, shadows, out, batch, hits, st, raysCast);
    next.clear();
    for (std::size_t i = 0; i < n; ++i)
      for (int j = 0; j < nSpawned[i]; ++j) next.push_back(spawned[i * maxSpawn + j]);
    std::swap(queue, next);
  }
}

}  // namespace cr
