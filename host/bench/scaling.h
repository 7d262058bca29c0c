// `cellray bench --scaling`: how build time, memory and the cost of a ray grow
// with scene size, on generated scenes from about 10^3 to 10^7 primitives
// (scene/generate.h: sphereflakes of depth 3..7, bumpy spheres of 10^3..10^7
// triangles), and Haines' "teapot in a stadium" (a sphereflake of depth 4 at
// the centre of a scene 10^4 times its size), where a uniform grid puts the
// whole object into a few cells.
#pragma once

#include <vector>

#include "host/bench/bench_options.h"
#include "host/bench/bench_scenes.h"

namespace cr::bench {

// The scenes of the study (quick: three small sizes of each family).
std::vector<SceneRef> ScalingScenes(bool quick);

// The configurations: every structure on the SIMD backend (robust), and
// Embree packet8 when available.
std::vector<Combo> ScalingCombos();

// Options of the study derived from a run's: primary and diffuse rays, three
// timed runs, statistics up to 2 x 10^6 primitives (the statistics tracer is
// a second structure in memory, and its run is slow on the largest sizes).
BenchOptions ScalingOptions(const BenchOptions& base);

}  // namespace cr::bench
