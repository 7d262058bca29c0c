#include "host/cl/cl_options.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>

#include <fmt/format.h>

#include "host/core/error.h"

namespace cr {

void ParseClVariant(const std::string& s, ClVariant& variant, bool& generic, int* tileW, int* tileH, ClBvhWalk* walk)
{
  std::string v = s;
  generic = false;
  if (walk) *walk = ClBvhWalk::Stack;
  if (tileW) *tileW = 0;
  if (tileH) *tileH = 0;
  const auto bad = [&] {
    return InputError(fmt::format("--variant '{}': the opencl backend has ray, stackless, wide and wide-packet (bvh), and packet, each also "
                                  "as ray-generic, ..., optionally with a work-group tile :WxH (e.g. packet:8x8)",
                                  s));
  };
  if (const auto colon = v.find(':'); colon != std::string::npos) {
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(v.c_str() + colon + 1, "%dx%d%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 1024 ||
        h > 1024)
      throw bad();
    if (tileW) *tileW = w;
    if (tileH) *tileH = h;
    v.resize(colon);
  }
  const std::string suffix = "-generic";
  if (v.size() >= suffix.size() && v.compare(v.size() - suffix.size(), suffix.size(), suffix) == 0) {
    generic = true;
    v.resize(v.size() - suffix.size());
  }
  if (v.empty() || v == "ray" || v == "stackless" || v == "wide" || v == "wide-packet") {
    variant = ClVariant::Ray;
    if (walk)
      *walk = v == "stackless" ? ClBvhWalk::Stackless
              : v == "wide"    ? ClBvhWalk::Wide
              : v == "wide-packet" ? ClBvhWalk::WidePacket
                                   : ClBvhWalk::Stack;
    return;
  }
  if (v == "packet") {
    variant = ClVariant::Packet;
    return;
  }
  throw bad();
}

const char* ClVariantName(ClVariant v) { return v == ClVariant::Packet ? "packet" : "ray"; }

const char* ClBvhWalkName(ClBvhWalk w, ClVariant v)
{
  return w == ClBvhWalk::Stackless    ? "stackless"
         : w == ClBvhWalk::Wide       ? "wide"
         : w == ClBvhWalk::WidePacket ? "wide-packet"
                                      : ClVariantName(v);
}

int ClRaysPerItem(ClBvhWalk w) { return w == ClBvhWalk::WidePacket ? 8 : 1; }

bool ClWalksWideBVH(const TraceConfig& config)
{
  if (config.accel != AccelKind::BVH) return false;
  ClVariant v = ClVariant::Ray;
  bool generic = false;
  ClBvhWalk walk = ClBvhWalk::Stack;
  try {
    ParseClVariant(config.variant, v, generic, nullptr, nullptr, &walk);
  } catch (const InputError&) {
    return false;
  }
  return walk == ClBvhWalk::Wide || walk == ClBvhWalk::WidePacket;
}

TraceConfig ClResolveDefaultVariant(const TraceConfig& config, const ClDevice& dev)
{
  TraceConfig c = config;
  if (c.variant.empty() && c.accel == AccelKind::BVH && dev.type == "cpu" && !dev.simulator) c.variant = "wide";
  return c;
}

ClProgramSpec MakeClProgramSpec(const Scene& scene, const TraceConfig& config, bool occlusion, bool camera,
                                const ClDevice& dev)
{
  ClProgramSpec s;
  int tileW = 0, tileH = 0;
  ParseClVariant(config.variant, s.variant, s.generic, &tileW, &tileH, &s.bvhWalk);
  if (s.bvhWalk != ClBvhWalk::Stack && config.accel != AccelKind::BVH)
    throw InputError(fmt::format("--variant {}: the {} walk is the BVH's (--accel bvh), not the {}'s", config.variant,
                                 ClBvhWalkName(s.bvhWalk, s.variant), AccelKindName(config.accel)));
  if (s.bvhWalk == ClBvhWalk::WidePacket && s.generic)
    throw InputError(fmt::format("--variant {}: the wide packet walk has no generic program", config.variant));
  if (config.precision == Precision::Fp64 && !dev.fp64)
    throw InputError(fmt::format("--precision fp64: OpenCL device '{}' has no cl_khr_fp64", dev.name));
  s.accel = config.accel;
  s.octreeMailbox = config.params.octreeMailbox == "on";
  s.octreeRayMargin = config.params.octreeMargin == "ray";
  s.anyHit = occlusion;
  s.camera = camera;
  s.unified = config.unifiedHits;
  s.precision = config.precision;
  s.stats = config.stats;
  s.cameraFp64 = dev.fp64;
  if (!s.generic) {
    s.motion = scene.hasMotion;
    s.types = 0;
    scene.ForEachType([&](const auto& pieces, std::uint32_t k) { s.types |= pieces.empty() ? 0u : 1u << k; });
    // CELLRAY_CL_TYPES=all compiles every primitive type in, whatever the
    // scene holds: one program per query serves every scene (a study over
    // many scenes, the test suites) at the price of the absent types' code.
    bool allTypes = false;
    if (const char* types = std::getenv("CELLRAY_CL_TYPES"); types && *types) {
      const std::string t = types;
      if (t == "all") {
        s.types = (1u << CR_NUM_PRIM_TYPES) - 1u;
        allTypes = true;
      } else if (t != "scene") {
        throw InputError(fmt::format("CELLRAY_CL_TYPES='{}': expected scene or all", t));
      }
    }
    // An SDF program holds only the distance operations its blocks use
    // (kernels/sdf.h CR_SDF_OPS), a CSG program the tests of its blocks'
    // leaf types only (kernels/csg.h CR_CSG_LEAVES); with every type
    // compiled in (CELLRAY_CL_TYPES=all), all of them, so that the one
    // program still serves every scene (the hard-case suite's SDF and CSG
    // scenes made 48 programs of 72 in a CI run before).
    if (((s.types >> CR_PRIM_SDF) & 1u) && !allTypes) {
      std::uint32_t ops = 0;
      for (const Sdf& b : scene.sdfs)
        for (std::uint32_t k = 0; k < b.count; ++k) ops |= 1u << b.op[k].op;
      if (!scene.sdfs.empty()) s.defines.push_back(fmt::format("CR_SDF_OPS={:#x}u", ops));
    }
    if (((s.types >> CR_PRIM_CSG) & 1u) && !scene.csgs.empty() && !allTypes) {
      std::uint32_t leaves = 0;
      for (const Csg& b : scene.csgs)
        for (std::uint32_t i = 0; i < b.nLeaves; ++i) leaves |= 1u << (b.leaf[i] & 255u);
      s.defines.push_back(fmt::format("CR_CSG_LEAVES={:#x}u", leaves));
    }
  }
  // A packet is one work-group, a screen tile of primary rays. On a CPU
  // (PoCL) 4x4: 16 lanes, one AVX-512 vector of floats; there 8x8 was up to
  // 35% slower, 4x2 within noise of 4x4 (docs/OPENCL.md, by structure). Elsewhere 8x8, an AMD wavefront or
  // two NVIDIA warps, not measured. Smaller where the device limits
  // work-groups.
  if (tileW > 0) {
    if (std::size_t(tileW) * std::size_t(tileH) > dev.maxWorkGroupSize)
      throw InputError(fmt::format("--variant {}: a {}x{} work-group exceeds the {} work-items of '{}'",
                                   config.variant, tileW, tileH, dev.maxWorkGroupSize, dev.name));
    s.packetW = tileW;
    s.packetH = tileH;
  } else {
    s.packetW = s.packetH = dev.type == "cpu" ? 4 : 8;
    if (std::size_t(s.packetW) * std::size_t(s.packetH) > dev.maxWorkGroupSize) {
      s.packetW = 8;
      s.packetH = static_cast<int>(dev.maxWorkGroupSize / 8 > 0 ? dev.maxWorkGroupSize / 8 : 1);
    }
  }
  // Cold paths (the exact fallbacks of the robust tests) are calls unless
  // CELLRAY_CL_COLD=inline asks for them inlined (CR_COLD_INLINE). On a GPU a
  // call's frame and the arrays passed to it live in scratch memory;
  // inlined, gfx906's robust packet kernels lose their 192-208 bytes of
  // scratch but those of triangle-only grids and octrees need 11 more VGPRs
  // and drop from 3 waves per SIMD to 2, the ray kernels 25-140 more
  // (bench/gpu_compile.py, docs/OPENCL.md). Neither form was timed on a GPU,
  // so the default stays as measured on PoCL. Refused on a CPU device other
  // than a simulator: PoCL 3.1's compiler crashes on inlined cone programs.
  if (const char* cold = std::getenv("CELLRAY_CL_COLD"); cold && *cold) {
    const std::string c = cold;
    if (c != "inline" && c != "call")
      throw InputError(fmt::format("CELLRAY_CL_COLD='{}': expected inline or call", c));
    if (c == "inline" && dev.type == "cpu" && !dev.simulator)
      throw InputError(fmt::format("CELLRAY_CL_COLD=inline: not on the CPU device '{}' (PoCL 3.1's compiler "
                                   "crashes on some inlined cold paths; docs/OPENCL.md)",
                                   dev.name));
    s.coldInline = c == "inline";
  }
  // For experiments on a kernel's variants (bench/ab_speed.py and by hand):
  // CELLRAY_CL_DEFINES="NAME=VALUE NAME2" adds -D options to every program
  // (and so to its cache key: host/cl/cl_program_cache.h).
  if (const char* defs = std::getenv("CELLRAY_CL_DEFINES"); defs && *defs) {
    std::string word;
    for (const char* c = defs;; ++c) {
      if (*c && *c != ' ') {
        if (!std::isalnum(static_cast<unsigned char>(*c)) && *c != '_' && *c != '=' && *c != '.' && *c != '-')
          throw InputError(fmt::format("CELLRAY_CL_DEFINES='{}': expected NAME or NAME=VALUE words", defs));
        word += *c;
      } else {
        if (!word.empty()) s.defines.push_back(word);
        word.clear();
        if (!*c) break;
      }
    }
  }
  return s;
}

std::string ClBuildOptions(const ClProgramSpec& s, const ClDevice& dev)
{
  std::string o = "-cl-std=CL1.2";
  if (dev.correctlyRoundedDivideSqrt) o += " -cl-fp32-correctly-rounded-divide-sqrt";
  if (s.precision == Precision::Fast) o += " -DCR_FAST";
  if (s.precision == Precision::Fp64) o += " -DCR_FP64";
  if (s.cameraFp64) o += " -DCR_CAMERA_FP64";
  if (s.stats) o += " -DCR_STATS";
  if (s.coldInline) o += " -DCR_COLD_INLINE";
  if (s.bvhWalk == ClBvhWalk::Stackless) o += " -DCR_BVH_STACKLESS";
  if (s.bvhWalk == ClBvhWalk::Wide || s.bvhWalk == ClBvhWalk::WidePacket) o += " -DCR_BVH_WIDE";
  if (s.bvhWalk == ClBvhWalk::WidePacket) o += " -DCR_BVH_WIDE_PACKET";
  if (s.octreeMailbox) o += " -DCR_OCTREE_MAILBOX_BUILD=1";
  if (s.octreeRayMargin) {
    o += " -DCR_OCTREE_MARGIN_BUILD=1";
    // Each level's parameters kept in private arrays on a CPU (PoCL: 35 ms
    // against 58 on the stadium), recomputed from the planes elsewhere (on a
    // GPU those arrays are scratch; kernels/octree.h CR_OCTREE_KEEP_FRAMES).
    o += dev.type == "cpu" ? " -DCR_OCTREE_KEEP_FRAMES=1" : " -DCR_OCTREE_KEEP_FRAMES=0";
  }
  o += fmt::format(" -DCR_PACKET_W={} -DCR_PACKET_H={}", s.packetW, s.packetH);
  if (!s.generic) {
#define CR_HAS_OPTION_(T, U, a) o += fmt::format(" -DCR_HAS_" #U "={}", (s.types >> CR_PRIM_##U) & 1u);
    CR_PRIM_TYPES(CR_HAS_OPTION_)
#undef CR_HAS_OPTION_
    o += fmt::format(" -DCR_HAS_MOTION={}", int(s.motion));
    switch (s.accel) {
#define CR_ACCEL_OPTION_(N, U, l, H, Nd) \
  case AccelKind::N: o += " -DCR_ACCEL_ONE -DCR_ACCEL_" #U; break;
      CR_ACCEL_TYPES(CR_ACCEL_OPTION_)
#undef CR_ACCEL_OPTION_
    }
    o += fmt::format(" -DCR_ANYHIT={} -DCR_UNIFIED={}", int(s.anyHit), int(s.unified));
    o += s.variant == ClVariant::Packet ? " -DCR_VARIANT_PACKET" : " -DCR_VARIANT_RAY";
    o += s.camera ? " -DCR_SOURCE_CAMERA" : " -DCR_SOURCE_RAYS";
  }
  for (const auto& d : s.defines) o += " -D" + d;
  return o;
}

}  // namespace cr
