// The path tracer (renderer.h): Kajiya's rendering equation by Monte Carlo,
// L_o = L_e + \int f L_i cos(theta) d(omega), one path per sample, traced as
// a wavefront: every bounce's rays in one closest-hit batch, their
// next-event shadow rays in one any-hit batch.
//
// At each vertex: the emission met (weighted against next-event estimation
// by the power heuristic unless the path arrived by a delta lobe or is the
// eye ray); one light chosen uniformly among the point and area lights and a
// shadow ray to it (a point light: its intensity over d^2; an area light: a
// point sampled on it, MIS-weighted against the BSDF's density; at the last
// vertex, which samples no BSDF, the light sample carries full weight); then
// one BSDF sample (bsdf.h) continues the path, its throughput an RGB triple;
// Russian roulette from the fourth vertex on.
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


struct PathState {
  RayRecord ray;
  glm::vec3 throughput;
  glm::dvec3 prevP;      // the vertex the ray left
  double pdfPrev = 0.0;  // density of its direction (non-delta BSDF mixture)
  std::uint32_t point = 0;
  std::uint8_t depth = 1;     // the eye ray is 1
  std::uint8_t specular = 1;  // arrived by a delta lobe (or is the eye ray)
};


// Random-number streams of vertex `depth`: 16 apart.
std::uint64_t Stream(int depth, int dim) { return 1000 + 16 * std::uint64_t(depth) + std::uint64_t(dim); }

}  // namespace

void PathChunk(const RenderContext& ctx, Tracer& tracer, std::uint64_t begin, std::uint64_t end, int k, glm::vec3* out,
               RenderStats& st, std::uint64_t& raysCast)
{
  const Scene& scene = ctx.scene;
  const RenderOptions& opt = ctx.opt;
  const std::size_t nPoint = scene.lights.size(), nArea = scene.areaLights.size();
  const std::size_t nLights = nPoint + nArea;
  std::vector<PathState> queue(end - begin), next;
  std::vector<HitRecord> hits;
  std::vector<ShadowRay> shadows;
  std::vector<PathState> cont;
  std::vector<std::uint8_t> alive;
  std::vector<glm::vec3> add;
  std::vector<RayRecord> batch;
  tbb::parallel_for(begin, end, [&](std::uint64_t pt) {
    PathState& s = queue[pt - begin];
    s.ray = ctx.CameraRay(pt, k);
    s.throughput = glm::vec3(1.0f);
    s.point = std::uint32_t(pt - begin);
  });

  while (!queue.empty()) {
    const std::size_t n = queue.size();
    TraceQueue(ctx, begin, k, tracer, queue, batch, hits, st, raysCast);
    const auto tb = std::chrono::steady_clock::now();
    shadows.assign(n, ShadowRay{});
    cont.resize(n);
    alive.assign(n, 0);
    add.assign(n, glm::vec3(0.0f));

    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      const PathState& ps = queue[i];
      const HitRecord& hit = hits[i];
      if (hit.prim == CR_NO_HIT) {
        add[i] = ps.throughput * scene.background;
        return;
      }
      const std::uint64_t sample = ctx.Sample(begin + ps.point, k);
      auto rnd = [&](int dim) { return ctx.Random(sample, Stream(ps.depth, dim)); };
      auto rnd2 = [&](int dim) {
        return ps.depth == 1 ? ctx.Stratified(begin + ps.point, k, Stream(1, dim)) : glm::dvec2(rnd(dim), rnd(dim + 2));
      };
      const std::uint32_t g = hit.prim;
      const std::uint32_t id = scene.IdOfHit(g, hit.u);
      const Material& m = scene.materials[scene.prims[id].material];
      const glm::dvec3 o(ps.ray.org[0], ps.ray.org[1], ps.ray.org[2]);
      const glm::dvec3 dd(ps.ray.dir[0], ps.ray.dir[1], ps.ray.dir[2]);
      const SurfacePoint sp = SurfaceAt(scene, g, o + double(hit.t) * dd, hit.u, hit.v, ctx.Time(begin + ps.point, k));
      const glm::dvec3 p(sp.p);
      const glm::dvec3 wo = -glm::normalize(dd);

      // Emission met: full weight after a delta lobe, else MIS against the
      // light sample taken at the previous vertex.
      if (m.light >= 0) {
        const AreaLight& light = scene.areaLights[std::size_t(m.light)];
        const glm::vec3 le = AreaLightEmission(light, dd);
        if (le != glm::vec3(0.0f)) {
          double w = 1.0;
          if (!ps.specular) w = PowerHeuristic(ps.pdfPrev, AreaLightPdf(light, ps.prevP, p) / double(nLights));
          add[i] += ps.throughput * le * float(w);
        }
      }

      const bool transmitter = m.transmittance > 0.0f;
      const bool facing = transmitter || ctx.twoSidedOpaque;
      glm::dvec3 ng(sp.ng), ns(sp.ns);
      const glm::dvec3 outward = ng;
      if (glm::dot(ng, wo) < 0.0) {
        if (!facing) return;  // the back of a one-sided opaque surface: black
        ng = -ng;
        ns = -ns;
      }
      const Bsdf bsdf = MakeBsdf(m, ns, outward);
      if (bsdf.Black()) return;
      const float offset = opt.robustOffsets ? sp.robustError : sp.error;
      const bool last = ps.depth >= opt.maxDepth;

      // Next-event estimation: one light, chosen uniformly.
      if (nLights && bsdf.HasSmooth()) {
        const std::size_t l = std::min(nLights - 1, std::size_t(rnd(0) * double(nLights)));
        ShadowRay& sh = shadows[i];
        sh.point = ps.point;
        sh.sourcePrim = id;
        sh.sourceOpaque = transmitter ? 0 : 1;
        if (l < nPoint) {
          const Light& light = scene.lights[l];
          const glm::dvec3 toL = glm::dvec3(light.position) - p;
          const double d2 = glm::dot(toL, toL);
          const glm::dvec3 wi = toL / std::sqrt(d2);
          const glm::vec3 f = EvalBsdf(bsdf, wo, wi);
          if (d2 > 0.0 && f != glm::vec3(0.0f)) {
            const glm::vec3 side = glm::dot(ng, wi) >= 0.0 ? glm::vec3(ng) : -glm::vec3(ng);
            const glm::vec3 so = OffsetRayOrigin(sp.p, offset, side);
            sh.ray = MakeRay(so, light.position - so, 1.0f);
            sh.light = ps.throughput * f * light.color *
                       float(ctx.pointIntensity * glm::dot(ns, wi) / d2 * double(nLights));
            sh.valid = 1;
          }
        } else {
          const AreaLight& light = scene.areaLights[l - nPoint];
          const glm::dvec2 u = rnd2(1);
          const LightSample ls = SampleAreaLight(light, p, u.x, u.y);
          if (ls.pdf > 0.0) {
            const glm::dvec3 wi = glm::normalize(ls.p - p);
            const glm::vec3 f = EvalBsdf(bsdf, wo, wi);
            if (f != glm::vec3(0.0f)) {
              const double pl = ls.pdf / double(nLights);
              const double w = last ? 1.0 : PowerHeuristic(pl, PdfBsdf(bsdf, wo, wi));
              const glm::vec3 side = glm::dot(ng, wi) >= 0.0 ? glm::vec3(ng) : -glm::vec3(ng);
              sh.ray = ShadowRayToLight(sp.p, offset, side, light, ls);
              sh.light = ps.throughput * f * ls.radiance * float(glm::dot(ns, wi) * w / pl);
              sh.valid = 1;
            }
          }
        }
      }
      if (last) return;

      // Continue by sampling the BSDF; Russian roulette from vertex 4 on.
      BsdfSample bs;
      const glm::dvec2 u = rnd2(5);
      if (!SampleBsdf(bsdf, wo, rnd(9), u.x, u.y, bs)) return;
      glm::vec3 thr = ps.throughput * bs.weight;
      if (ps.depth >= 3) {
        const float q = std::min(0.95f, std::max({thr.r, thr.g, thr.b}));
        if (!(rnd(10) < q)) return;
        thr /= q;
      }
      if (!(std::max({thr.r, thr.g, thr.b}) > 0.0f)) return;
      PathState& nx = cont[i];
      const glm::vec3 side = glm::dot(ng, bs.wi) >= 0.0 ? glm::vec3(ng) : -glm::vec3(ng);
      nx.ray = MakeRay(OffsetRayOrigin(sp.p, offset, side), glm::vec3(bs.wi), INFINITY);
      nx.throughput = thr;
      nx.prevP = p;
      nx.pdfPrev = bs.pdf;
      nx.point = ps.point;
      nx.depth = std::uint8_t(ps.depth + 1);
      nx.specular = bs.delta ? 1 : 0;
      alive[i] = 1;
    });

    for (std::size_t i = 0; i < n; ++i) {
      out[queue[i].point] += add[i];
      const bool hit = hits[i].prim != CR_NO_HIT;
      if (queue[i].depth == 1)
        st.eyeRays++, st.eyeHits += hit;
      else
        st.pathRays++, st.pathHits += hit;
    }
    st.shadeMs += MsSince(tb);
    TraceShadows(ctx, begin, k, tracer, shadows, out, batch, hits, st, raysCast);
    next.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (alive[i]) next.push_back(cont[i]);
    std::swap(queue, next);
  }
}

}  // namespace cr
