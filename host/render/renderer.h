// The renderer: integrators written as a wavefront over any Tracer. Each
// bounce traces one queue of rays (closest hit), shades it on the host,
// traces the queue of shadow rays it spawned (any hit), and compacts the
// surviving rays into the next queue, so every trace launch is a batch the
// backend traces as packets, on every structure and backend alike.
//
// Integrators (docs/RENDERING.md):
//  whitted  Whitted ray tracing (Hearn & Baker 14-6): Phong illumination from
//           point lights with shadow rays, reflection and refraction trees;
//           with the distributed effects of Cook, Porter & Carpenter (1984):
//           area lights sampled over their area (soft shadows), a thin lens,
//           the pixel, all stratified over the samples of a pixel; and, with
//           --diffuse, the hypercube paper's one-bounce diffuse
//           interreflection (cube:N) or K cosine-distributed rays (cosine:K);
//  path     a path tracer for the rendering equation (Kajiya 1986):
//           next-event estimation to area and point lights with multiple
//           importance sampling (power heuristic), the BSDF of bsdf.h,
//           Russian roulette after three bounces.
// Samples are taken in passes of one sample per pixel, so a long render can
// show its image every N passes and stop at a time limit with a valid one.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/scene/scene.h"
#include "host/trace/tracer.h"

namespace cr {

enum class Sides { Auto, One, Two };
enum class Integrator { Whitted, Path };

// --diffuse: the first hit's diffuse interreflection in the Whitted
// integrator. Cube: rays through the N x N cells of each face of a cube
// around the hit point (a jittered point in each cell) that lie above the
// surface, each weighted by its share of Kd colour cos(theta) / pi over the
// cell's solid angle; Cosine: K cosine-distributed rays of weight Kd colour /
// K. The rays they spawn gather direct light only (one bounce).
struct DiffuseGather {
  enum class Kind { None, Cube, Cosine } kind = Kind::None;
  int n = 0;
  int Rays() const { return kind == Kind::Cube ? 6 * n * n : kind == Kind::Cosine ? n : 0; }
};
// "cube:N" or "cosine:K" (InputError otherwise).
DiffuseGather ParseDiffuse(const std::string& s);

struct Image;

struct RenderOptions {
  int width = 0, height = 0;  // 0: the scene camera's resolution
  int spp = 1;                // samples per pixel (stratified jitter), outside SPD mode
  int maxDepth = 5;           // the eye ray is depth 1
  bool spd = false;           // the SPD procedure (../shared/SPD.md)
  bool fresnel = false;       // Schlick-weighted reflection/refraction (not in SPD mode)
  Sides sides = Sides::Auto;  // Auto: double-sided when the scene has patches (SPD's teapot rule)
  std::uint64_t seed = 1;
  bool progress = false;      // progress bar on stderr
  // Secondary ray origins offset by SurfacePoint::robustError (a few ulps of
  // the hit point): right for our robust and fp64 tracers; Embree and the
  // fast mode need the float bound SurfacePoint::error (scene/surface.h).
  bool robustOffsets = true;
  Integrator integrator = Integrator::Whitted;
  DiffuseGather diffuse;
  // Progressive output: every `writeEvery` passes (0: never) `onImage` gets
  // the image so far; with timeLimit > 0 (seconds) the render stops after
  // the last pass finished within it (at least one pass), discarding the
  // pass in flight.
  int writeEvery = 0;
  std::function<void(const Image&, int passes)> onImage;
  double timeLimit = 0.0;
  // Part of the image only (distributed rendering, host/cli/cmd_render.cpp):
  // when set, the render covers the image rows this hands out, [y0, y1) per
  // call, until it returns false, each band with all its samples at once
  // (no progressive output, no time limit); the other rows stay 0. A
  // pixel's value does not depend on which rows are rendered with it.
  std::function<bool(int& y0, int& y1)> nextRows;
};

// Ray counts of a render: how many rays of each kind were cast and how many
// hit something (for shadow rays: how many were blocked).
struct RenderStats {
  std::uint64_t eyeRays = 0, eyeHits = 0;
  std::uint64_t reflectionRays = 0, reflectionHits = 0;
  std::uint64_t refractionRays = 0, refractionHits = 0;
  std::uint64_t shadowRays = 0, shadowHits = 0;
  // Hits on transmitters where Snell's law has no solution: no refraction
  // ray is cast there (the reflection ray is). The published SPD refraction
  // counts include these events: refractionRays + totalInternalReflections
  // is the figure to compare with them.
  std::uint64_t totalInternalReflections = 0;
  std::uint64_t selfShadowed = 0;  // shadow rays of opaque surfaces blocked by their own primitive
  std::uint64_t diffuseRays = 0, diffuseHits = 0;  // --diffuse gather rays
  std::uint64_t pathRays = 0, pathHits = 0;        // path tracer: rays after the eye ray
  int passes = 0;                                   // samples per pixel done
  bool timeLimited = false;                         // stopped by the time limit
  double traceMs = 0.0, shadeMs = 0.0, totalMs = 0.0;
};
void to_json(nlohmann::json& j, const RenderStats& s);
// Another part's counts added to s (parts of one image: the times are the
// slower part's, the passes the same).
void AddRenderStats(RenderStats& s, const RenderStats& part);

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // linear, row-major from the top
};

// Renders with `tracer`, which must have been created with unifiedHits on.
Image Render(const Scene& scene, Tracer& tracer, const RenderOptions& opt, RenderStats* stats);

}  // namespace cr
