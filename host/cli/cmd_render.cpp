// render: Whitted ray tracing of a scene to PNG or EXR.
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

namespace cr::cli {

Run RegisterRender(CLI::App& app)
{
  struct O {
    std::string scene, out = "out.png", size, statsPath, sides = "auto";
    int spp = 1, depth = 5;
    bool spd = false, fresnel = false, noProgress = false;
    std::uint64_t seed = 1;
    TracerOptions t;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("render", "Render a scene (Whitted: shadows, reflection, refraction) to PNG or EXR");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj)")->required();
  cmd->add_option("-o,--output", o->out, "Output image (.png: 8-bit sRGB, .exr: float linear)")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WxH (default: the scene's resolution)");
  cmd->add_option("--spp", o->spp, "Samples per pixel, stratified jitter (not in SPD mode)")->capture_default_str();
  cmd->add_option("--depth", o->depth, "Maximum ray-tree depth, the eye ray being 1")->capture_default_str();
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
    ro.maxDepth = o->depth;
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
    Scene scene = LoadScene(o->scene);
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
