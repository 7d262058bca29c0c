// Whitted ray tracing (Hearn & Baker 14-6): Phong illumination with shadow
// rays, reflection and refraction trees, written as a wavefront over any
// Tracer: each bounce traces one queue of rays (closest hit), shades it on the
// host, traces the queue of shadow rays it spawned (any hit), and compacts the
// surviving reflection and refraction rays into the next queue. Every trace
// launch is therefore a batch the backend traces as packets.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "host/scene/scene.h"
#include "host/trace/tracer.h"

namespace cr {

enum class Sides { Auto, One, Two };

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
  double traceMs = 0.0, shadeMs = 0.0, totalMs = 0.0;
};
void to_json(nlohmann::json& j, const RenderStats& s);

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // linear, row-major from the top
};

// Renders with `tracer`, which must have been created with unifiedHits on.
Image Render(const Scene& scene, Tracer& tracer, const RenderOptions& opt, RenderStats* stats);

}  // namespace cr
