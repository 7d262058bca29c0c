// What one OpenCL program models, and the build options that say it
// (kernels/trace.cl lists them). Model only what a scene and query need: the
// primitive types present, the one structure, the query kind, the precision,
// the variant; a generic program (all types, runtime arguments) exists for
// comparison.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/cl/cl_device.h"
#include "host/trace/tracer.h"

namespace cr {

enum class ClVariant { Ray, Packet };
// How the per-ray kernel walks the BVH (kernels/bvh.h): with a stack (the
// default), without one (CR_BVH_STACKLESS; --variant stackless), or through
// the SIMD backend's 8-wide layout with float8 (CR_BVH_WIDE; --variant wide,
// for CPU devices: kernels/bvh_wide.cl), and that layout with 8 rays per
// work-item (CR_BVH_WIDE_PACKET; --variant wide-packet).
enum class ClBvhWalk { Stack, Stackless, Wide, WidePacket };
// Rays per work-item of the rays kernel (wide-packet: 8).
int ClRaysPerItem(ClBvhWalk w);

struct ClProgramSpec {
  bool generic = false;          // all primitive types and structures, query by argument
  std::uint32_t types = ~0u;     // bit k: the program has primitive type k (CR_PRIM_*)
  bool motion = true;            // moving pieces and ray times (CR_HAS_MOTION, kernels/motion.h)
  AccelKind accel = AccelKind::BVH;
  bool anyHit = false;
  bool unified = false;
  Precision precision = Precision::Robust;
  bool stats = false;
  ClVariant variant = ClVariant::Ray;
  ClBvhWalk bvhWalk = ClBvhWalk::Stack;  // the per-ray kernel's BVH walk (--variant stackless, wide)
  bool octreeMailbox = false;    // the octree walks with its mailbox (CR_OCTREE_MAILBOX_BUILD; --octree-mailbox on)
  bool octreeRayMargin = false;  // the octree walks with the ray's margins (CR_OCTREE_MARGIN_BUILD; --octree-margin ray)
  bool camera = false;           // primary rays generated on the device, else rays from a buffer
  int packetW = 8, packetH = 8;  // work-group tile (the packet of the packet kernels)
  bool cameraFp64 = false;       // primary rays in double, bit-equal to the host's
  bool coldInline = false;       // cold paths inlined (CR_COLD_INLINE; CELLRAY_CL_COLD=inline)
  // Hook for the renderer's kernels: extra "NAME=VALUE" definitions (material
  // count, light count), appended as -D options.
  std::vector<std::string> defines;
};

// The spec for tracing `scene` with `config` (query kind `occlusion`) on
// `dev`. InputError when the device cannot do it (fp64 without cl_khr_fp64,
// an unknown --variant).
// `camera`: the program traces primary rays it generates (TracePrimary).
ClProgramSpec MakeClProgramSpec(const Scene& scene, const TraceConfig& config, bool occlusion, bool camera,
                                const ClDevice& dev);

// "-cl-std=CL1.2 -DCR_ACCEL_BVH ...": never fast-math flags; correctly
// rounded divide and sqrt where the device offers them (the C++ build rounds
// that way), so that results match the scalar backend bit for bit.
std::string ClBuildOptions(const ClProgramSpec& spec, const ClDevice& dev);

// Parses --variant: "", "ray", "stackless" (the ray kernel with the BVH
// walked without a stack), "wide" (the ray kernel with the BVH's 8-wide
// layout), "wide-packet" (the same, 8 rays per work-item), "packet", optionally suffixed "-generic", then
// optionally ":WxH", the work-group tile (packet size; tileW, tileH 0 when
// absent: the device's default, see MakeClProgramSpec).
void ParseClVariant(const std::string& s, ClVariant& variant, bool& generic, int* tileW = nullptr,
                    int* tileH = nullptr, ClBvhWalk* walk = nullptr);
const char* ClVariantName(ClVariant v);
// "stackless", "wide"; the stack walk: ClVariantName's.
const char* ClBvhWalkName(ClBvhWalk w, ClVariant v);
// Whether the OpenCL backend walks the BVH's 8-wide layout for `config`
// (--accel bvh --variant wide): it then builds with the SIMD backend's
// parameters (BackendAccelParams).
bool ClWalksWideBVH(const TraceConfig& config);
// `config` with the backend's default walk filled in on `dev`: without a
// --variant, the BVH on a CPU device (PoCL) takes the wide walk, 1.6-1.8x
// the stack walk's rate there with the same answers (docs/OPENCL.md, "The
// default walk"); GPUs, accelerators and Oclgrind keep the stack walk, which
// `--variant ray` names everywhere.
TraceConfig ClResolveDefaultVariant(const TraceConfig& config, const ClDevice& dev);

}  // namespace cr
