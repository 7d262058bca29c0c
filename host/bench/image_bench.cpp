#include "host/bench/image_bench.h"

#include <chrono>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/error.h"
#include "host/render/image_io.h"
#include "host/render/renderer.h"

namespace cr::bench {

namespace {

Image RenderWith(const Scene& scene, Tracer& tracer, const RenderOptions& base, int w, int h, int spp, double& ms,
                 std::uint64_t& rays)
{
  RenderOptions ro = base;
  ro.width = w;
  ro.height = h;
  ro.spp = spp;
  RenderStats st;
  const auto t0 = std::chrono::steady_clock::now();
  Image img = Render(scene, tracer, ro, &st);
  ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  rays = st.eyeRays + st.reflectionRays + st.refractionRays + st.shadowRays + st.diffuseRays + st.pathRays;
  return img;
}

std::unique_ptr<Tracer> MakeTracer(const Scene& scene, const Combo& c, const AccelParams& params)
{
  TraceConfig cfg;
  cfg.params = params;
  cfg.backend = c.backend;
  cfg.accel = c.accel;
  cfg.precision = c.precision;
  cfg.variant = c.variant;
  cfg.unifiedHits = true;
  return CreateTracer(scene, cfg);
}

}  // namespace

void to_json(nlohmann::json& j, const ImageRow& r)
{
  j = nlohmann::json{{"scene", r.scene},
                     {"label", r.label},
                     {"integrator", r.integrator},
                     {"backend", BackendName(r.combo.backend)},
                     {"accel", r.combo.backend == Backend::Embree ? "embree-bvh" : AccelKindName(r.combo.accel)},
                     {"precision", r.combo.backend == Backend::Embree ? "embree" : PrecisionName(r.combo.precision)},
                     {"variant", r.combo.variant},
                     {"spp", r.spp},
                     {"width", r.width},
                     {"height", r.height},
                     {"render_ms", r.renderMs},
                     {"rays", r.rays},
                     {"psnr", r.psnr},
                     {"mean_error", r.meanError},
                     {"rms_error", r.rmsError},
                     {"mean_error_same_spp", r.meanErrorSame},
                     {"note", r.note}};
  if (r.psnrSame)
    j["psnr_same_spp"] = *r.psnrSame;
  else
    j["psnr_same_spp"] = nullptr;  // identical to the reference's render: infinite PSNR
}

std::vector<ImageRow> RunImageBench(const SceneRef& sref, const ImageBenchOptions& o,
                                    const std::function<void(const std::string&)>& progress)
{
  const Scene scene = LoadBenchScene(sref);
  std::vector<Combo> combos = o.combos;
  if (combos.empty()) {
    combos = {Combo{Backend::Simd, AccelKind::BVH, Precision::Robust, ""},
              Combo{Backend::Simd, AccelKind::BVH, Precision::Fast, ""},
              Combo{Backend::Scalar, AccelKind::BVH, Precision::Fp64, ""}};
    if (EmbreeAvailable()) combos.push_back(Combo{Backend::Embree, AccelKind::BVH, Precision::Robust, "single"});
  }
  const Combo refCombo{Backend::Reference, AccelKind::BVH, Precision::Fp64, ""};
  auto refTracer = MakeTracer(scene, refCombo, o.params);
  RenderOptions test;
  test.integrator = o.integrator;
  test.diffuse = o.diffuse;
  test.maxDepth = o.maxDepth > 0 ? o.maxDepth : o.integrator == Integrator::Path ? 8 : 5;
  test.robustOffsets = true;
  RenderOptions refOpt = test;
  if (o.diffuse.kind != DiffuseGather::Kind::None) {
    refOpt.integrator = Integrator::Path;
    refOpt.diffuse = DiffuseGather{};
    refOpt.maxDepth = 2;
  }
  const std::string integratorName =
      std::string(o.integrator == Integrator::Path ? "path" : "whitted") +
      (o.diffuse.kind == DiffuseGather::Kind::Cube     ? fmt::format(" cube:{}", o.diffuse.n)
       : o.diffuse.kind == DiffuseGather::Kind::Cosine ? fmt::format(" cosine:{}", o.diffuse.n)
                                                       : std::string());
  double ms = 0.0;
  std::uint64_t rays = 0;
  if (progress) progress(fmt::format("images: {} reference at {} spp ({}x{})", sref.name, o.referenceSpp, o.width, o.height));
  const Image high = RenderWith(scene, *refTracer, refOpt, o.width, o.height, o.referenceSpp, ms, rays);
  auto save = [&](const Image& img, const std::string& name) {
    if (o.imageDir.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(o.imageDir, ec);
    WriteImage((std::filesystem::path(o.imageDir) / name).string(), img.width, img.height, img.rgb);
  };
  save(high, fmt::format("{}-reference-{}spp.png", sref.name, o.referenceSpp));
  std::vector<ImageRow> rows;
  std::vector<Image> sameRef;
  for (int spp : o.spps) sameRef.push_back(RenderWith(scene, *refTracer, test, o.width, o.height, spp, ms, rays));
  for (const Combo& c : combos) {
    std::unique_ptr<Tracer> tracer;
    std::string skip;
    try {
      tracer = MakeTracer(scene, c, o.params);
    } catch (const std::exception& e) {
      skip = fmt::format("skipped: {}", e.what());
    }
    for (std::size_t si = 0; si < o.spps.size(); ++si) {
      ImageRow r;
      r.scene = sref.name;
      r.label = c.Label();
      r.integrator = integratorName;
      r.combo = c;
      r.spp = o.spps[si];
      r.width = o.width;
      r.height = o.height;
      if (!tracer) {
        r.note = skip;
        rows.push_back(r);
        continue;
      }
      RenderOptions ro = test;
      ro.robustOffsets = c.backend != Backend::Embree && c.precision != Precision::Fast;
      const Image img = RenderWith(scene, *tracer, ro, o.width, o.height, r.spp, r.renderMs, r.rays);
      const ImageDiff d = CompareImages(o.width, o.height, img.rgb, high.rgb);
      r.psnr = d.psnr;
      r.meanError = d.meanError;
      r.rmsError = d.rmsError;
      const ImageDiff s = CompareImages(o.width, o.height, img.rgb, sameRef[si].rgb);
      if (std::isfinite(s.psnr)) r.psnrSame = s.psnr;
      r.meanErrorSame = s.meanError;
      std::string file = r.label;
      for (char& ch : file)
        if (ch == ' ') ch = '-';
      save(img, fmt::format("{}-{}-{}spp.png", sref.name, file, r.spp));
      if (progress)
        progress(fmt::format("images: {} {} spp {}: {:.1f} ms, PSNR {:.2f} dB vs {} spp reference", sref.name, r.label,
                             r.spp, r.renderMs, r.psnr, o.referenceSpp));
      rows.push_back(r);
    }
  }
  return rows;
}

}  // namespace cr::bench
