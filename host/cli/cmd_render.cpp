// render: a scene to PNG or EXR by the Whitted or the path-tracing integrator.
#include <fstream>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/render/image_io.h"
#include "host/render/renderer.h"
#include "host/scene/area_light.h"

namespace cr::cli {

Run RegisterRender(CLI::App& app)
{
  struct O {
    std::string scene, out = "out.png", size, statsPath, sides = "auto", integrator = "whitted", diffuse;
    int spp = 1, depth = 0, writeEvery = 0;
    double areaLights = 0.0, timeLimit = 0.0;
    bool spd = false, fresnel = false, noProgress = false;
    std::uint64_t seed = 1;
    TracerOptions t;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "render", "Render a scene to PNG or EXR (Whitted with distributed effects, or a path tracer; docs/RENDERING.md)");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj)")->required();
  cmd->add_option("-o,--output", o->out, "Output image (.png: 8-bit sRGB, .exr: float linear)")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WxH (default: the scene's resolution)");
  cmd->add_option("--integrator", o->integrator, "whitted (point and area lights, mirrors, glass, --diffuse) or path")
      ->capture_default_str();
  cmd->add_option("--spp", o->spp,
                  "Samples per pixel (1..65536), stratified over the pixel, the lens and the area lights (not in SPD mode)")
      ->capture_default_str();
  cmd->add_option("--depth", o->depth,
                  "Maximum ray-tree depth / path vertices, the eye ray being 1 (default: 5 whitted, 8 path)");
  cmd->add_option("--diffuse", o->diffuse,
                  "Whitted: one-bounce diffuse interreflection at the first hit, cube:N (the hypercube paper's N x N "
                  "cells per cube face) or cosine:K (K cosine-distributed rays)");
  cmd->add_option("--area-lights", o->areaLights,
                  "Turn every point light into a sphere light of this radius (soft shadows; docs/RENDERING.md)");
  cmd->add_option("--write-every", o->writeEvery, "Write the image so far every N passes (one sample per pixel each)");
  cmd->add_option("--time-limit", o->timeLimit,
                  "Stop after the last pass finished within this many seconds; the image holds the passes done");
  cmd->add_flag("--spd", o->spd, "SPD procedure: 513x513 corner rays averaged to 512x512, depth 5 (../shared/SPD.md)");
  cmd->add_flag("--fresnel", o->fresnel, "Schlick Fresnel weights for reflection/refraction (not in SPD mode)");
  cmd->add_option("--sides", o->sides, "Opaque surfaces one- or two-sided: auto (two if the scene has patches), one, two")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the jitter")->capture_default_str();
  cmd->add_option("--stats", o->statsPath, "Write ray statistics (JSON) to this file");
  cmd->add_flag("--no-progress", o->noProgress, "No progress bar on stderr");
  AddTracerOptions(cmd, o->t);
  return [o]() {
    TraceConfig cfg = o->t.ToConfig();
    cfg.unifiedHits = true;
    std::unique_ptr<tbb::global_control> limit;
    if (cfg.threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, cfg.threads);
    RenderOptions ro;
    if (!o->size.empty()) ParseSize(o->size, ro.width, ro.height);
    ro.spp = o->spp;
    if (o->integrator == "whitted") ro.integrator = Integrator::Whitted;
    else if (o->integrator == "path") ro.integrator = Integrator::Path;
    else throw InputError(fmt::format("--integrator '{}': expected whitted or path", o->integrator));
    ro.maxDepth = o->depth > 0 ? o->depth : ro.integrator == Integrator::Path ? 8 : 5;
    if (o->depth < 0) throw InputError(fmt::format("--depth {} is not in 1..64", o->depth));
    if (!o->diffuse.empty()) ro.diffuse = ParseDiffuse(o->diffuse);
    ro.writeEvery = o->writeEvery;
    ro.timeLimit = o->timeLimit;
    ro.spd = o->spd;
    ro.fresnel = o->fresnel;
    ro.seed = o->seed;
    ro.progress = !o->noProgress;
    ro.robustOffsets = cfg.backend != Backend::Embree && cfg.precision != Precision::Fast;
    if (o->sides == "auto") ro.sides = Sides::Auto;
    else if (o->sides == "one") ro.sides = Sides::One;
    else if (o->sides == "two") ro.sides = Sides::Two;
    else throw InputError(fmt::format("--sides '{}': expected auto, one or two", o->sides));
    if (ro.spd && (ro.spp != 1 || o->fresnel)) throw InputError("--spd fixes one sample per pixel corner and no Fresnel");
    if (o->areaLights < 0.0) throw InputError(fmt::format("--area-lights {}: the radius must be > 0", o->areaLights));
    Scene scene = LoadScene(o->scene);
    if (o->areaLights > 0.0) PointLightsToSpheres(scene, o->areaLights);
    ro.onImage = [o](const Image& img, int passes) {
      WriteImage(o->out, img.width, img.height, img.rgb);
      if (!o->noProgress) std::cerr << fmt::format("cellray: {} passes: wrote {}\n", passes, o->out);
    };
    auto tracer = CreateTracer(scene, cfg);
    RenderStats stats;
    Image img = Render(scene, *tracer, ro, &stats);
    WriteImage(o->out, img.width, img.height, img.rgb);
    nlohmann::json j{{"scene", o->scene},
                     {"output", o->out},
                     {"backend", BackendName(tracer->ActiveBackend())},
                     {"accel", cfg.backend == Backend::Reference ? "reference-bvh" : AccelKindName(cfg.accel)},
                     {"device", tracer->DeviceName()},
                     {"width", img.width},
                     {"height", img.height},
                     {"spp", ro.spd ? 1 : ro.spp},
                     {"passes", stats.passes},
                     {"integrator", o->integrator},
                     {"diffuse", o->diffuse.empty() ? nlohmann::json(nullptr) : nlohmann::json(o->diffuse)},
                     {"area_lights", scene.areaLights.size()},
                     {"time_limited", stats.timeLimited},
                     {"spd", ro.spd},
                     {"build_ms", tracer->Info().buildMs},
                     {"stats", stats}};
    if (!tracer->FallbackReason().empty()) {
      j["fallback_from"] = "opencl";
      j["fallback_reason"] = tracer->FallbackReason();
    }
    if (!o->statsPath.empty()) {
      std::string text = j.dump(2) + "\n";
      WriteFileAtomically(o->statsPath, text.data(), text.size());
    }
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
