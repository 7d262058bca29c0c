// Samples per pixel against image error: renders (render/renderer.h)
// of one scene at spp 1, 4, 16, ... with several configurations, compared
// (render/image_io.h CompareImages: PSNR, mean absolute error, after display
// encoding) with a high-spp render by the fp64 reference backend, and with
// the reference's render at the same spp and seed, which isolates the
// arithmetic of a configuration from the sampling noise.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/bench/bench_options.h"
#include "host/bench/bench_scenes.h"
#include "host/render/renderer.h"

namespace cr::bench {

struct ImageBenchOptions {
  int width = 96, height = 96;
  std::vector<int> spps = {1, 4, 16};
  int referenceSpp = 64;
  std::vector<Combo> combos;  // empty: simd bvh robust and fast, scalar bvh fp64, embree single
  std::string imageDir;       // when set, the renders are written there as PNG
  // What renders: the Whitted integrator (reference: Whitted on the fp64
  // backend), with --diffuse (reference: the path tracer limited to two
  // vertices, the same light transport), or the path tracer (reference: the
  // path tracer), maxDepth vertices.
  Integrator integrator = Integrator::Whitted;
  DiffuseGather diffuse;
  int maxDepth = 0;  // 0: 5 for Whitted, 8 for the path tracer
  AccelParams params;  // the structures' parameters (the reference's too)
};

struct ImageRow {
  std::string scene, label, integrator;
  Combo combo;
  int spp = 0, width = 0, height = 0;
  double renderMs = 0.0;
  std::uint64_t rays = 0;  // every ray the render cast
  double psnr = 0.0, meanError = 0.0, rmsError = 0.0;  // against the high-spp reference
  std::optional<double> psnrSame;  // against the reference at the same spp (absent: identical images)
  double meanErrorSame = 0.0;
  std::string note;
};
void to_json(nlohmann::json& j, const ImageRow& r);

std::vector<ImageRow> RunImageBench(const SceneRef& scene, const ImageBenchOptions& options,
                                    const std::function<void(const std::string&)>& progress);

}  // namespace cr::bench
