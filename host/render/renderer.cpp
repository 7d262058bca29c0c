#include "host/render/renderer.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "host/core/error.h"
#include "host/rays/raygen.h"
#include "host/render/integrator.h"
#include "host/render/progress.h"
#include "host/render/sampling.h"
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
                     {"diffuse_rays", s.diffuseRays},
                     {"diffuse_hits", s.diffuseHits},
                     {"path_rays", s.pathRays},
                     {"path_hits", s.pathHits},
                     {"passes", s.passes},
                     {"time_limited", s.timeLimited},
                     {"trace_ms", s.traceMs},
                     {"shade_ms", s.shadeMs},
                     {"total_ms", s.totalMs}};
}

void AddRenderStats(RenderStats& s, const RenderStats& p)
{
  s.eyeRays += p.eyeRays, s.eyeHits += p.eyeHits;
  s.reflectionRays += p.reflectionRays, s.reflectionHits += p.reflectionHits;
  s.refractionRays += p.refractionRays, s.refractionHits += p.refractionHits;
  s.shadowRays += p.shadowRays, s.shadowHits += p.shadowHits;
  s.totalInternalReflections += p.totalInternalReflections;
  s.selfShadowed += p.selfShadowed;
  s.diffuseRays += p.diffuseRays, s.diffuseHits += p.diffuseHits;
  s.pathRays += p.pathRays, s.pathHits += p.pathHits;
  s.timeLimited = s.timeLimited || p.timeLimited;
  s.traceMs = std::max(s.traceMs, p.traceMs);
  s.shadeMs = std::max(s.shadeMs, p.shadeMs);
  s.totalMs = std::max(s.totalMs, p.totalMs);
}

DiffuseGather ParseDiffuse(const std::string& s)
{
  DiffuseGather g;
  const auto colon = s.find(':');
  const std::string kind = s.substr(0, colon);
  int n = 0;
  bool ok = colon != std::string::npos;
  if (ok) {
    const char* b = s.data() + colon + 1;
    const char* e = s.data() + s.size();
    auto [p, ec] = std::from_chars(b, e, n);
    ok = ec == std::errc() && p == e && b != e;
  }
  if (kind == "cube" && ok && n >= 1 && n <= 32) {
    g.kind = DiffuseGather::Kind::Cube;
  } else if (kind == "cosine" && ok && n >= 1 && n <= 4096) {
    g.kind = DiffuseGather::Kind::Cosine;
  } else {
    throw InputError(fmt::format("--diffuse '{}': expected cube:N (N in 1..32) or cosine:K (K in 1..4096)", s));
  }
  g.n = n;
  return g;
}

double RenderContext::Random(std::uint64_t sample, std::uint64_t stream) const
{
  return ToUnit(HashRandom(opt.seed, stream, sample));
}

glm::dvec2 RenderContext::Stratified(std::uint64_t point, int k, std::uint64_t stream) const
{
  const std::uint64_t s = Sample(point, k);
  const std::uint32_t order = std::uint32_t(HashRandom(opt.seed, stream + 1, point));
  const std::uint32_t stratum = Permute(std::uint32_t(k), std::uint32_t(opt.spp), order);
  const int kx = int(stratum) % sx, ky = int(stratum) / sx;
  return {(kx + Random(s, stream)) / sx, std::min(0.99999999999999989, (ky + Random(s, stream + 2)) / sy)};
}

RayRecord RenderContext::CameraRay(std::uint64_t point, int k) const
{
  const int x = int(point % std::uint64_t(cw)), y = int(point / std::uint64_t(cw));
  const std::uint64_t s = Sample(point, k);
  double px, py;
  if (opt.spd) {
    px = x - 0.5;
    py = y - 0.5;
  } else if (opt.spp == 1) {
    px = x;
    py = y;
  } else {
    const int kx = k % sx, ky = k / sx;
    px = x - 0.5 + (kx + ToUnit(HashRandom(opt.seed, 41, s))) / sx;
    py = y - 0.5 + (ky + ToUnit(HashRandom(opt.seed, 42, s))) / sy;
  }
  if (!(frame.aperture > 0.0)) return PrimaryRay(frame, px, py);
  const glm::dvec2 lens = Stratified(point, k, 43);
  return LensRay(frame, px, py, lens.x, lens.y);
}

float RenderContext::Time(std::uint64_t point, int k) const
{
  if (!scene.hasMotion) return 0.0f;
  const std::uint64_t s = Sample(point, k);
  const std::uint32_t order = std::uint32_t(HashRandom(opt.seed, 45, point));
  const std::uint32_t stratum = Permute(std::uint32_t(k), std::uint32_t(opt.spp), order);
  // Below 1 in float: the shutter interval is half-open.
  return std::min(0.99999994f, float((stratum + Random(s, 44)) / double(opt.spp)));
}

void TraceShadows(const RenderContext& ctx, std::uint64_t begin, int k, Tracer& tracer, std::vector<ShadowRay>& shadows,
                  glm::vec3* out, std::vector<RayRecord>& batch, std::vector<HitRecord>& hits, RenderStats& st,
                  std::uint64_t& raysCast)
{
  const Scene& scene = ctx.scene;
  std::size_t ns = 0;
  for (std::size_t i = 0; i < shadows.size(); ++i)
    if (shadows[i].valid) shadows[ns++] = shadows[i];
  shadows.resize(ns);
  if (!ns) return;
  const auto t0 = std::chrono::steady_clock::now();
  batch.resize(ns);
  for (std::size_t i = 0; i < ns; ++i) batch[i] = shadows[i].ray;
  std::vector<float> times;
  ctx.Times(shadows, begin, k, times);
  tracer.Trace(batch, times, hits, true, nullptr);
  st.shadowRays += ns;
  raysCast += ns;
  for (std::size_t i = 0; i < ns; ++i) {
    if (hits[i].prim == CR_NO_HIT) {
      out[shadows[i].point] += shadows[i].light;
    } else {
      st.shadowHits++;
      if (shadows[i].sourceOpaque && scene.IdOfHit(hits[i].prim, hits[i].u) == shadows[i].sourcePrim) st.selfShadowed++;
    }
  }
  st.traceMs += MsSince(t0);
}

Image Render(const Scene& scene, Tracer& tracer, const RenderOptions& optIn, RenderStats* statsOut)
{
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  RenderOptions opt = optIn;
  if (opt.spd) {
    opt.spp = 1;
    opt.maxDepth = 5;
    opt.fresnel = false;
    if (opt.integrator != Integrator::Whitted || opt.diffuse.kind != DiffuseGather::Kind::None)
      throw InputError("--spd is the Whitted integrator without --diffuse");
  }
  if (opt.spp < 1 || opt.spp > 65536) throw InputError(fmt::format("--spp {} is not in 1..65536", opt.spp));
  if (opt.maxDepth < 1 || opt.maxDepth > 64) throw InputError(fmt::format("--depth {} is not in 1..64", opt.maxDepth));
  if (opt.writeEvery < 0) throw InputError(fmt::format("--write-every {} is negative", opt.writeEvery));
  if (!(opt.timeLimit >= 0.0)) throw InputError(fmt::format("--time-limit {} is negative", opt.timeLimit));
  if (opt.integrator == Integrator::Path && opt.diffuse.kind != DiffuseGather::Kind::None)
    throw InputError("--diffuse belongs to the whitted integrator (the path tracer samples all interreflection)");
  const int w = opt.width > 0 ? opt.width : scene.camera.width;
  const int h = opt.height > 0 ? opt.height : scene.camera.height;
  RenderContext ctx{scene, opt, MakeCameraFrame(scene.camera, w, h)};
  ctx.cw = opt.spd ? w + 1 : w;
  ctx.ch = opt.spd ? h + 1 : h;
  ctx.sx = std::max(1, int(std::ceil(std::sqrt(double(opt.spp)))));
  ctx.sy = (opt.spp + ctx.sx - 1) / ctx.sx;
  ctx.twoSidedOpaque =
      opt.sides == Sides::Two || (opt.sides == Sides::Auto && scene.CountKind(PrimKind::kPatch, CR_PRIM_TRIANGLE) > 0);
  {
    ctx.intensity = float(SpdLightIntensity(scene.lights.size()));
    // A point light in the path tracer: the radiant intensity that gives a
    // diffuse surface at the centre of the scene what the SPD shading gives
    // it (the limit of render --area-lights, host/scene/area_light.h).
    const glm::dvec3 mid = LightMatchPoint(scene);
    double d2 = 0.0;
    for (const Light& l : scene.lights) d2 += glm::dot(glm::dvec3(l.position) - mid, glm::dvec3(l.position) - mid);
    if (!scene.lights.empty()) d2 /= double(scene.lights.size());
    ctx.pointIntensity = float(kPi * ctx.intensity * std::max(d2, 1e-30));
  }

  const std::uint64_t nPoints = std::uint64_t(ctx.cw) * std::uint64_t(ctx.ch);
  // Rays in flight per chunk: bounded so that the queues stay within memory.
  const std::uint64_t perPoint = 2 + std::uint64_t(opt.diffuse.Rays()) + scene.lights.size() + scene.areaLights.size();
  const std::uint64_t kChunk = std::max<std::uint64_t>(4096, (std::uint64_t(1) << 21) / perPoint);
  RenderStats st;
  std::vector<glm::vec3> accum(nPoints, glm::vec3(0.0f)), pass(nPoints);
  Progress progress(nPoints * std::uint64_t(opt.spp), opt.progress);
  const auto t0 = Clock::now();
  std::uint64_t raysCast = 0;

  auto makeImage = [&](int passes) {
    Image img;
    img.width = w;
    img.height = h;
    img.rgb.assign(std::size_t(w) * h * 3, 0.0f);
    tbb::parallel_for(0, h, [&](int y) {
      for (int x = 0; x < w; ++x) {
        glm::vec3 c(0.0f);
        if (opt.spd) {
          const std::size_t cw = std::size_t(ctx.cw);
          c = 0.25f * (accum[std::size_t(y) * cw + x] + accum[std::size_t(y) * cw + x + 1] +
                       accum[std::size_t(y + 1) * cw + x] + accum[std::size_t(y + 1) * cw + x + 1]);
        } else {
          c = accum[std::size_t(y) * w + x] / float(passes);
        }
        for (int a = 0; a < 3; ++a) img.rgb[(std::size_t(y) * w + x) * 3 + a] = c[a];
      }
    });
    return img;
  };

  // Sample k of points [pb, pe) into pass[pb, pe), chunk by chunk; returns
  // false when the time limit stopped it (the pass in flight is discarded).
  auto samplePoints = [&](std::uint64_t pb, std::uint64_t pe, int k, bool mayStop) {
    for (std::uint64_t begin = pb; begin < pe; begin += kChunk) {
      const std::uint64_t end = std::min(pe, begin + kChunk);
      std::fill(pass.begin() + std::ptrdiff_t(begin), pass.begin() + std::ptrdiff_t(end), glm::vec3(0.0f));
      if (opt.integrator == Integrator::Path)
        PathChunk(ctx, tracer, begin, end, k, pass.data() + begin, st, raysCast);
      else
        WhittedChunk(ctx, tracer, begin, end, k, pass.data() + begin, st, raysCast);
      progress.Update(std::uint64_t(k) * nPoints + end, raysCast);
      if (mayStop && k > 0 && opt.timeLimit > 0.0 && ms(t0, Clock::now()) > 1000.0 * opt.timeLimit && end < pe)
        return false;
    }
    return true;
  };

  if (opt.nextRows) {
    if (opt.writeEvery > 0 || opt.timeLimit > 0.0)
      throw InputError("--write-every and --time-limit apply to a render by one process");
    // Band by band, every sample of a band's points at once; SPD mode's
    // pixels read the corner points of the row below too.
    int y0 = 0, y1 = 0;
    while (opt.nextRows(y0, y1)) {
      const std::uint64_t pb = std::uint64_t(y0) * std::uint64_t(ctx.cw);
      const std::uint64_t pe = std::min(nPoints, std::uint64_t(opt.spd ? y1 + 1 : y1) * std::uint64_t(ctx.cw));
      // A corner row two bands share is computed again, to the same values.
      std::fill(accum.begin() + std::ptrdiff_t(pb), accum.begin() + std::ptrdiff_t(pe), glm::vec3(0.0f));
      for (int k = 0; k < opt.spp; ++k) {
        samplePoints(pb, pe, k, false);
        for (std::uint64_t i = pb; i < pe; ++i) accum[i] += pass[i];
      }
    }
    st.passes = opt.spp;
  } else {
    for (int k = 0; k < opt.spp; ++k) {
      if (!samplePoints(0, nPoints, k, true)) {
        st.timeLimited = true;
        break;
      }
      for (std::uint64_t i = 0; i < nPoints; ++i) accum[i] += pass[i];
      st.passes = k + 1;
      if (opt.onImage && opt.writeEvery > 0 && st.passes % opt.writeEvery == 0 && st.passes < opt.spp)
        opt.onImage(makeImage(st.passes), st.passes);
      if (opt.timeLimit > 0.0 && st.passes < opt.spp && ms(t0, Clock::now()) > 1000.0 * opt.timeLimit) {
        st.timeLimited = true;
        break;
      }
    }
  }
  progress.Finish(raysCast);
  Image img = makeImage(st.passes);
  st.totalMs = ms(t0, Clock::now());
  if (statsOut) *statsOut = st;
  return img;
}

}  // namespace cr
