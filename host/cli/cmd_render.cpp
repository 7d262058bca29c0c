// render: until the Whitted renderer lands, a hit-depth image of the primary
// rays (near surfaces bright, misses black).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "cli/commands.h"
#include "core/error.h"
#include "rays/raygen.h"
#include "render/image_io.h"
#include "scene/camera.h"

namespace cr::cli {

Run RegisterRender(CLI::App& app)
{
  struct O {
    std::string scene, out = "out.png", size;
    TracerOptions t;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("render", "Render a scene to an image (currently: hit depth of primary rays)");
  cmd->add_option("scene", o->scene, "Scene file (.nff or .obj)")->required();
  cmd->add_option("-o,--output", o->out, "Output image (.png or .exr)")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WxH (default: the scene's resolution)");
  AddTracerOptions(cmd, o->t);
  return [o]() {
    TraceConfig cfg = o->t.ToConfig();
    std::unique_ptr<tbb::global_control> limit;
    if (cfg.threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, cfg.threads);
    Scene scene = LoadScene(o->scene);
    RayGenOptions g;
    if (!o->size.empty()) ParseSize(o->size, g.width, g.height);
    const int w = g.width ? g.width : scene.camera.width, h = g.height ? g.height : scene.camera.height;
    auto tracer = CreateTracer(scene, cfg);
    std::vector<HitRecord> hits;
    // Device backends generate the primary rays where they trace them.
    tracer->TracePrimary(MakeCameraFrame(scene.camera, w, h), w, h, hits, nullptr);
    float tmin = INFINITY, tmax = 0.0f;
    for (const auto& hr : hits)
      if (hr.prim != CR_NO_HIT) {
        tmin = std::min(tmin, hr.t);
        tmax = std::max(tmax, hr.t);
      }
    std::vector<float> rgb(std::size_t(w) * h * 3, 0.0f);
    for (std::size_t i = 0; i < hits.size(); ++i) {
      if (hits[i].prim == CR_NO_HIT) continue;
      float s = tmax > tmin ? (hits[i].t - tmin) / (tmax - tmin) : 0.0f;
      float v = 1.0f - 0.85f * s;
      rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = v * v;
    }
    WriteImage(o->out, w, h, rgb);
    std::size_t nHit = std::count_if(hits.begin(), hits.end(), [](const HitRecord& x) { return x.prim != CR_NO_HIT; });
    nlohmann::json j{{"scene", o->scene}, {"output", o->out}, {"width", w}, {"height", h}, {"rays", hits.size()},
                     {"hits", nHit}, {"image", "hit depth"}};
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
