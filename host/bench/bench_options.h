// What `cellray bench` measures: the options of one run and the
// configurations (backend x structure x precision x variant) it times.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/accel/accel.h"
#include "host/rays/raygen.h"
#include "host/trace/tracer.h"

namespace cr::bench {

// One traced configuration. `variant` is passed to the backend as is (empty:
// the backend's default).
struct Combo {
  Backend backend = Backend::Simd;
  AccelKind accel = AccelKind::BVH;
  Precision precision = Precision::Robust;
  std::string variant;
  // Short name for tables: "simd bvh", "opencl bvh packet", "embree packet8",
  // "scalar bvh fast".
  std::string Label() const;
};

struct BenchOptions {
  std::vector<std::string> scenes;  // names or paths; empty: the defaults (ResolveScenes)
  // Empty lists mean the defaults of DefaultCombos.
  std::vector<AccelKind> accels;
  std::vector<Backend> backends;
  std::vector<Precision> precisions;
  std::vector<RayKind> kinds = {RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::Random};
  int repeat = 5;                 // timed runs per row (median, min, max)
  // Timed runs taken in rounds across every row of a scene (each round runs
  // each row once), so that a drift of the machine's speed during the run
  // falls on every configuration alike; scenes above interleaveMaxPieces run
  // each row's timed runs back to back (every configuration's structure would
  // be held at once). false: back to back everywhere.
  bool interleave = true;
  std::uint64_t interleaveMaxPieces = 1000000;
  std::uint64_t rays = 1u << 16;  // rays per set (primary: an image of about this many pixels)
  std::string outDir = "bench-out";
  int threads = 0;                // 0: all cores
  std::string device;             // OpenCL device ("N" or "platform:device"), empty: the default
  bool quick = false;             // CI size: few rays, one repeat, no image study
  bool images = true;             // spp against image error
  bool plots = true;              // run bench/plot.py when python3 and matplotlib are there
  bool stats = true;              // Havran's per-ray measures (a separate, untimed run)
  std::uint64_t statsMaxPieces = ~std::uint64_t(0);  // no statistics run above this scene size
  std::uint64_t seed = 1;
  std::string commandLine;        // recorded in results.json
  // The SDF axis: every scene with SDF blocks runs once per combination of
  // these, each block's hit threshold, relaxation and step budget replaced
  // (the row's scene is then NAME@eps=E,w=W,steps=N); empty: the scene's own.
  std::vector<double> sdfEps, sdfRelax;
  std::vector<long> sdfSteps;
  AccelParams params;  // the structures' parameters for every row (CR_ACCEL_PARAMS; default: the builders')
};

// The configurations a run times, in table order. With no explicit lists:
// every structure on the default SIMD backend (robust) and on OpenCL's
// per-ray variant, the BVH packet variants, Embree single and packet8 (and
// its robust flag), and the precision sweep on the BVH: scalar fast, robust,
// fp64; simd fast; opencl fast and fp64 (when the device has it). Explicit
// lists run their full cross product (variants: each backend's defaults).
std::vector<Combo> PlanCombos(const BenchOptions& options, bool openclHasFp64, bool openclAvailable);

}  // namespace cr::bench
