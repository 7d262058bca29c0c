// The `opencl` backend: the portable kernels compiled by the device's OpenCL
// compiler (kernels/trace.cl), one program per query kind, specialised to the
// scene (cl_options.h) and cached on disk (cl_program_cache.h). The scene and
// the structure are uploaded once; rays per Trace call (or generated on the
// device for TracePrimary); hits and per-ray counters are read back.
#include <chrono>
#include <cstring>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/cl/cl_context.h"
#include "host/cl/cl_fault.h"
#include "host/cl/cl_options.h"
#include "host/cl/cl_program.h"
#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/trace/tracer.h"
#include "simd/bvh_wide_builder.h"

namespace cr {

namespace {

// Positions of the kernel arguments (kernels/trace.cl CR_SCENE_PARAMS and
// the kernels' own parameters after them): type k's array at 2k, its count
// at 2k + 1, then the primitive ids and the structures.
enum SceneArg : cl_uint {
  kArgPrimIds = 2 * CR_NUM_PRIM_TYPES,
  kArgMotion,
  kArgAccelArrays,  // structure s: header, nodes, references at kArgAccelArrays + 3 s
  kArgAccel = kArgAccelArrays + 3 * CR_NUM_ACCEL_TYPES,
  kArgAnyHit,
  kArgUnified,
  kNumSceneArgs
};
enum RaysArg : cl_uint {
  kArgRays = kNumSceneArgs,
  kArgNRays,
  kArgRaysHits,
  kArgRaysStats,
  kArgTimes,
  kArgHasTimes,
  kArgRaysPool  // the packet kernel's local memory (kernels/trace.cl CR_PACKET_LOCALS)
};
enum PrimaryArg : cl_uint {
  kArgOrg = kNumSceneArgs,
  kArgForward,
  kArgRight,
  kArgUp,
  kArgTanHalf,
  kArgTmin,
  kArgWidth,
  kArgHeight,
  kArgPrimaryHits,
  kArgPrimaryStats,
  kArgPrimaryPool  // as kArgRaysPool
};

// The `accel` argument: the structure's position in CR_ACCEL_TYPES.
int AccelArg(AccelKind k) { return static_cast<int>(k); }

template <typename T>
void SetArg(cl::Kernel& k, cl_uint index, const T& value, const char* kernelName)
{
  CR_CL_CHECK_WHAT(k.setArg(index, value), "clSetKernelArg", fmt::format("{} argument {}", kernelName, index));
}

// kernels/ray.h TraceStats: four uint counters per ray (nIT, nTS, nLeaves,
// nEmptyLeaves), the layout the kernels write.
constexpr std::size_t kStatsBytes = 4 * sizeof(std::uint32_t);

std::size_t RoundUp(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

double MsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

class ClTracer final : public Tracer {
 public:
  ClTracer(const Scene& scene, const TraceConfig& cfg)
      : scene_(scene), cl_(CreateClContext(cfg.device))
  {
    // Without --variant, the device's default walk (the BVH's wide walk on
    // a CPU device).
    config_ = ClResolveDefaultVariant(cfg, cl_.dev);
    ParseClVariant(config_.variant, variant_, generic_);
    // Validate the device and options before the (slow) structure build.
    const ClProgramSpec spec = MakeClProgramSpec(scene, config_, false, false, cl_.dev);
    tileW_ = spec.packetW;
    tileH_ = spec.packetH;
    walk_ = spec.bvhWalk;
    AccelData data = BuildAccel(scene, config_.accel, BackendAccelParams(scene, config_));
    if (walk_ == ClBvhWalk::Stackless) AddBVHParents(data.bvh, data.info);
    info_ = data.info;
    Upload(data);
    if (walk_ == ClBvhWalk::Wide || walk_ == ClBvhWalk::WidePacket) UploadWide(data);
  }

  void Prepare(bool occlusion, bool primary) override { (void)Program(occlusion && !primary, primary); }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    Built& p = Program(occlusion, false);
    hits.resize(rays.size());
    if (rays.empty()) return;
    const std::size_t n = rays.size();
    if (n > 0xFFFFFFFFu) throw RuntimeError("OpenCL: more than 2^32 - 1 rays in one batch");
    // A CPU device shares the host's memory: its kernel reads the caller's rays and writes the hits where
    // they are (CL_MEM_USE_HOST_PTR; a blocking map of the hits then makes them the host's), instead of
    // a copy of each into a buffer and back. Other devices copy.
    const bool inPlace = cl_.dev.type == "cpu";
    EnsureRayBuffers(n, !inPlace);
    cl::Buffer rayBuf = rayBuf_, hitBuf = hitBuf_;
    if (inPlace) {
      rayBuf = ClWrapHost(cl_, "rays", const_cast<RayRecord*>(rays.data()), n * sizeof(RayRecord), CL_MEM_READ_ONLY);
      hitBuf = ClWrapHost(cl_, "hits", hits.data(), n * sizeof(HitRecord), CL_MEM_WRITE_ONLY);
    } else {
      CR_CL_CHECK_WHAT(cl_.queue.enqueueWriteBuffer(rayBuf_, CL_FALSE, 0, n * sizeof(RayRecord), rays.data()),
                       "clEnqueueWriteBuffer", "rays");
    }
    cl::Kernel& k = p.rays;
    SetArg(k, kArgRays, rayBuf, p.raysName);
    SetArg(k, kArgNRays, cl_uint(n), p.raysName);
    SetArg(k, kArgRaysHits, hitBuf, p.raysName);
    SetArg(k, kArgRaysStats, config_.stats ? statsBuf_ : dummy_, p.raysName);
    const bool timed = !times.empty() && scene_.hasMotion;
    if (timed) {
      if (times.size() != n) throw RuntimeError(fmt::format("OpenCL: {} ray times for {} rays", times.size(), n));
      EnsureTimeBuffer(n);
      CR_CL_CHECK_WHAT(cl_.queue.enqueueWriteBuffer(timeBuf_, CL_FALSE, 0, n * sizeof(float), times.data()),
                       "clEnqueueWriteBuffer", "ray times");
    }
    SetArg(k, kArgTimes, timed ? timeBuf_ : dummy_, p.raysName);
    SetArg(k, kArgHasTimes, cl_int(timed ? 1 : 0), p.raysName);
    const std::size_t local = std::size_t(p.spec.packetW) * std::size_t(p.spec.packetH);
    // fp64 programs walk each ray alone (kernels/trace.cl).
    const std::size_t per = p.spec.precision == Precision::Fp64 ? 1 : std::size_t(ClRaysPerItem(walk_));
    Launch(k, cl::NDRange(RoundUp((n + per - 1) / per, local)), cl::NDRange(local), p.raysName);
    ReadBack(n, hits, stats, inPlace ? &hitBuf : nullptr);
  }

  void TracePrimary(const CameraFrame& frame, int width, int height, std::vector<HitRecord>& hits,
                    TraceStatsSum* stats) override
  {
    Built& p = Program(false, true);
    if (width <= 0 || height <= 0) {
      hits.clear();
      return;
    }
    const std::size_t n = std::size_t(width) * std::size_t(height);
    hits.resize(n);
    EnsureRayBuffers(n, false);
    cl::Kernel& k = p.primary;
    SetPrimaryArgs(k, p, frame, width, height);
    SetArg(k, kArgPrimaryHits, hitBuf_, p.primaryName);
    SetArg(k, kArgPrimaryStats, config_.stats ? statsBuf_ : dummy_, p.primaryName);
    const std::size_t lw = std::size_t(p.spec.packetW), lh = std::size_t(p.spec.packetH);
    Launch(k, cl::NDRange(RoundUp(std::size_t(width), lw), RoundUp(std::size_t(height), lh)), cl::NDRange(lw, lh),
           p.primaryName);
    ReadBack(n, hits, stats);
  }

  std::string DeviceName() const override { return cl_.dev.name; }

  double LastKernelMs() const override { return lastKernelMs_; }

  std::string VariantName() const override
  {
    return fmt::format("{} {}{} {}x{}", PrecisionName(config_.precision),
                       ClBvhWalkName(walk_, variant_),
                       generic_ ? " generic" : "", tileW_, tileH_);
  }

  void Describe(nlohmann::json& j) const override
  {
    double buildMs = 0.0, jitMs = 0.0;
    bool allHit = true;
    std::size_t binaryBytes = 0;
    std::string note, options;
    for (const auto& b : built_) {
      if (!b) continue;
      buildMs += b->program.buildMs;
      jitMs += b->jitMs;
      allHit = allHit && b->program.cacheHit;
      binaryBytes += b->program.binaryBytes;
      if (!b->program.cacheHit && note.empty()) note = b->program.cacheNote;
      options = b->program.options;
    }
    j["device_index"] = fmt::format("{}:{}", cl_.dev.platformIndex, cl_.dev.deviceIndex);
    j["program_build_ms"] = buildMs;
    j["program_cache"] = allHit ? "hit" : "miss";
    if (!allHit) j["program_cache_note"] = note;
    j["program_binary_bytes"] = binaryBytes;
    j["kernel_first_launch_ms"] = jitMs;
    j["build_options"] = options;
  }

 private:
  // One program and its kernels: Trace_Rays* (rays from a buffer) and/or
  // Trace_Primary* (camera rays generated on the device).
  struct Built {
    ClProgramSpec spec;
    ClProgram program;
    cl::Kernel rays, primary;
    const char* raysName = "";
    const char* primaryName = "";
    bool hasRays = false, hasPrimary = false;
    std::size_t poolBytes = 0;  // the packet kernels' local memory (Trace_PacketPoolBytes)
    double jitMs = 0.0;  // first (empty) launches: drivers that compile per work-group size do it here
  };

  // Programs are specialised to the query kind and the ray source, built on
  // first use: rays closest, rays occlusion, camera. A generic program
  // serves all three.
  Built& Program(bool occlusion, bool camera)
  {
    const std::size_t slot = generic_ ? 0 : camera ? 2 : (occlusion ? 1 : 0);
    if (!built_[slot]) built_[slot] = Build(occlusion, camera);
    Built& b = *built_[slot];
    if (b.hasRays) SetArg(b.rays, kArgAnyHit, cl_int(occlusion), b.raysName);
    if (b.hasPrimary) SetArg(b.primary, kArgAnyHit, cl_int(0), b.primaryName);
    return b;
  }

  std::unique_ptr<Built> Build(bool occlusion, bool camera)
  {
    auto b = std::make_unique<Built>();
    b->spec = MakeClProgramSpec(scene_, config_, occlusion, camera, cl_.dev);
    const bool packet = b->spec.variant == ClVariant::Packet;
    b->hasRays = generic_ || !camera;
    b->hasPrimary = generic_ || camera;
    b->raysName = packet ? "Trace_RaysPacket" : "Trace_Rays";
    b->primaryName = packet ? "Trace_PrimaryPacket" : "Trace_Primary";
    std::vector<std::string> names;
    if (b->hasRays) names.push_back(b->raysName);
    if (b->hasPrimary) names.push_back(b->primaryName);
    if (packet) names.push_back(kPoolBytesName);
    b->program = BuildClProgram(cl_.context, cl_.dev, ClKernelSource(), ClBuildOptions(b->spec, cl_.dev), names);
    const std::size_t lw = std::size_t(b->spec.packetW), lh = std::size_t(b->spec.packetH);
    const auto t0 = std::chrono::steady_clock::now();
    if (packet) b->poolBytes = PacketPoolBytes(b->program.kernels.back());
    // First launches, empty (no ray, 0x0 image): a driver that compiles each
    // kernel for its work-group size (PoCL) does it now, not in a timed Trace.
    std::size_t next = 0;
    if (b->hasRays) {
      b->rays = b->program.kernels[next++];
      if (packet) SetArg(b->rays, kArgRaysPool, cl::Local(b->poolBytes), b->raysName);
      CheckKernel(*b, b->rays, b->raysName);
      SetArg(b->rays, kArgAnyHit, cl_int(occlusion), b->raysName);
      SetArg(b->rays, kArgRays, dummy_, b->raysName);
      SetArg(b->rays, kArgNRays, cl_uint(0), b->raysName);
      SetArg(b->rays, kArgRaysHits, dummy_, b->raysName);
      SetArg(b->rays, kArgRaysStats, dummy_, b->raysName);
      SetArg(b->rays, kArgTimes, dummy_, b->raysName);
      SetArg(b->rays, kArgHasTimes, cl_int(0), b->raysName);
      Launch(b->rays, cl::NDRange(lw * lh), cl::NDRange(lw * lh), b->raysName);
    }
    if (b->hasPrimary) {
      b->primary = b->program.kernels[next++];
      if (packet) SetArg(b->primary, kArgPrimaryPool, cl::Local(b->poolBytes), b->primaryName);
      CheckKernel(*b, b->primary, b->primaryName);
      SetArg(b->primary, kArgAnyHit, cl_int(0), b->primaryName);
      SetPrimaryArgs(b->primary, *b, MakeCameraFrame(scene_.camera, 1, 1), 0, 0);
      SetArg(b->primary, kArgPrimaryHits, dummy_, b->primaryName);
      SetArg(b->primary, kArgPrimaryStats, dummy_, b->primaryName);
      Launch(b->primary, cl::NDRange(lw, lh), cl::NDRange(lw, lh), b->primaryName);
    }
    CR_CL_CHECK(cl_.queue.finish(), "clFinish");
    b->jitMs = MsSince(t0);
    return b;
  }

  static constexpr const char* kPoolBytesName = "Trace_PacketPoolBytes";

  // The bytes of local memory the program's packet kernels take as their
  // last argument, as the program computes them (kernels/trace.cl
  // CR_PACKET_POOL_BYTES: the pieces depend on the build's precision,
  // structure and packet size).
  std::size_t PacketPoolBytes(cl::Kernel& k)
  {
    cl_int err = CL_SUCCESS;
    cl::Buffer out(cl_.context, CL_MEM_WRITE_ONLY, sizeof(cl_uint), nullptr, &err);
    CR_CL_CHECK_WHAT(err, "clCreateBuffer", kPoolBytesName);
    SetArg(k, 0, out, kPoolBytesName);
    Launch(k, cl::NDRange(1), cl::NDRange(1), kPoolBytesName);
    cl_uint bytes = 0;
    CR_CL_CHECK_WHAT(cl_.queue.enqueueReadBuffer(out, CL_TRUE, 0, sizeof bytes, &bytes), "clEnqueueReadBuffer",
                     kPoolBytesName);
    if (bytes == 0u) throw RuntimeError(fmt::format("OpenCL: {} reported 0 bytes of local memory", kPoolBytesName));
    return bytes;
  }

  // Binds the scene to a kernel of the program and checks it against the
  // device's limits for this kernel before any launch: a work-group of the
  // packet's size (CL_KERNEL_WORK_GROUP_SIZE; a launch would fail with
  // CL_INVALID_WORK_GROUP_SIZE) and its local memory (CL_KERNEL_LOCAL_MEM_SIZE
  // against CL_DEVICE_LOCAL_MEM_SIZE; a launch would fail with
  // CL_OUT_OF_RESOURCES).
  void CheckKernel(const Built& b, cl::Kernel& k, const char* name)
  {
    BindScene(k, name);
    std::size_t wg = 0;
    CR_CL_CHECK_WHAT(k.getWorkGroupInfo(cl_.dev.device, CL_KERNEL_WORK_GROUP_SIZE, &wg), "clGetKernelWorkGroupInfo",
                     name);
    const bool wgFault = ClFaultInjected(ClFault::Limits);
    if (wgFault) wg = 1;
    const std::size_t need = std::size_t(b.spec.packetW) * std::size_t(b.spec.packetH);
    if (wg < need)
      throw RuntimeError(fmt::format("OpenCL: CL_INVALID_WORK_GROUP_SIZE: kernel {} runs at most {} work-items per "
                                     "group on {} (CL_KERNEL_WORK_GROUP_SIZE), fewer than the {}x{} it needs{}",
                                     name, wg, cl_.dev.name, b.spec.packetW, b.spec.packetH,
                                     wgFault ? ClFaultNote(ClFault::Limits) : ""));
    cl_ulong local = 0;
    CR_CL_CHECK_WHAT(k.getWorkGroupInfo(cl_.dev.device, CL_KERNEL_LOCAL_MEM_SIZE, &local), "clGetKernelWorkGroupInfo",
                     name);
    const bool localFault = ClFaultInjected(ClFault::LocalMem);
    const std::uint64_t limit = localFault ? 0 : cl_.dev.localMemBytes;
    if (local > limit || localFault)
      throw RuntimeError(fmt::format("OpenCL: CL_OUT_OF_RESOURCES: kernel {} needs {} bytes of local memory; {} "
                                     "offers {} (CL_DEVICE_LOCAL_MEM_SIZE){}",
                                     name, local, cl_.dev.name, limit,
                                     localFault ? ClFaultNote(ClFault::LocalMem) : ""));
  }

  // Enqueues a kernel (global and local ranges from offset 0).
  void Launch(cl::Kernel& k, const cl::NDRange& global, const cl::NDRange& local, const char* name)
  {
    if (ClFaultInjected(ClFault::Launch))
      ThrowClError(CL_OUT_OF_RESOURCES, "clEnqueueNDRangeKernel", __FILE__, __LINE__,
                   name + ClFaultNote(ClFault::Launch));
    CR_CL_CHECK_WHAT(cl_.queue.enqueueNDRangeKernel(k, cl::NullRange, global, local, nullptr, &lastLaunch_),
                     "clEnqueueNDRangeKernel", name);
  }

  // The last launch's device time (its event, complete once a blocking read
  // after it returned); negative where the device does not report it.
  double KernelMs(const cl::Event& e)
  {
    cl_ulong start = 0, end = 0;
    if (e.getProfilingInfo(CL_PROFILING_COMMAND_START, &start) != CL_SUCCESS ||
        e.getProfilingInfo(CL_PROFILING_COMMAND_END, &end) != CL_SUCCESS || end < start)
      return -1.0;
    return double(end - start) * 1e-6;
  }

  void BindScene(cl::Kernel& k, const char* name)
  {
    const PrimRanges r = scene_.Ranges();
    for (cl_uint t = 0; t < CR_NUM_PRIM_TYPES; ++t) {
      SetArg(k, 2 * t, prims_[t], name);
      SetArg(k, 2 * t + 1, cl_uint(Prim_Count(&r, t)), name);
    }
    SetArg(k, kArgPrimIds, primIds_, name);
    if (hasMotion_) {
      SetArg(k, kArgMotion, motion_, name);
    } else {
      // A static scene: a null pointer (OpenCL 1.2 allows one for a global
      // buffer argument), which a generic program's kernels/motion.h tests.
      const cl_mem none = nullptr;
      CR_CL_CHECK_WHAT(k.setArg(kArgMotion, sizeof(cl_mem), &none), "clSetKernelArg",
                       fmt::format("{} argument {}", name, unsigned(kArgMotion)));
    }
    for (cl_uint a = 0; a < 3 * CR_NUM_ACCEL_TYPES; ++a) SetArg(k, kArgAccelArrays + a, accel_[a], name);
    SetArg(k, kArgAccel, cl_int(AccelArg(config_.accel)), name);
    SetArg(k, kArgUnified, cl_int(config_.unifiedHits ? 1 : 0), name);
  }

  void SetPrimaryArgs(cl::Kernel& k, const Built& b, const CameraFrame& f, int width, int height)
  {
    const char* name = b.primaryName;
    cl_float4 org = {{float(f.eye.x), float(f.eye.y), float(f.eye.z), 0.0f}};
    SetArg(k, kArgOrg, org, name);
    const glm::dvec3* vecs[3] = {&f.forward, &f.right, &f.up};
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3& v = *vecs[i];
      if (b.spec.cameraFp64) {
        cl_double4 d = {{v.x, v.y, v.z, 0.0}};
        SetArg(k, kArgForward + cl_uint(i), d, name);
      } else {
        cl_float4 d = {{float(v.x), float(v.y), float(v.z), 0.0f}};
        SetArg(k, kArgForward + cl_uint(i), d, name);
      }
    }
    if (b.spec.cameraFp64)
      SetArg(k, kArgTanHalf, cl_double(f.tanHalf), name);
    else
      SetArg(k, kArgTanHalf, cl_float(f.tanHalf), name);
    SetArg(k, kArgTmin, cl_float(f.hither), name);
    SetArg(k, kArgWidth, cl_int(width), name);
    SetArg(k, kArgHeight, cl_int(height), name);
  }

  void Upload(const AccelData& d)
  {
    dummy_ = ClUpload(cl_, "placeholder", nullptr, 0);
    const std::vector<std::uint32_t> ids = scene_.UnifiedIds();
    scene_.ForEachType([&](const auto& pieces, std::uint32_t t) {
      prims_[t] = ClUpload(cl_, PrimTypeName(t), pieces.data(), pieces.size() * sizeof(pieces[0]));
    });
    primIds_ = ClUpload(cl_, "primitive ids", ids.data(), ids.size() * sizeof(std::uint32_t));
    const std::vector<float> motion = scene_.UnifiedMotion();
    hasMotion_ = !motion.empty();
    if (hasMotion_) motion_ = ClUpload(cl_, "motion", motion.data(), motion.size() * sizeof(float));
    for (auto& b : accel_) b = dummy_;
    // The built structure's header, nodes and references (the others keep
    // the placeholder).
    auto upload = [&](std::size_t s, const char* lower, const auto& data) {
      const auto& nodes = data.Nodes();
      accel_[3 * s] = ClUpload(cl_, fmt::format("{} header", lower).c_str(), &data.header, sizeof(data.header));
      accel_[3 * s + 1] = ClUpload(cl_, fmt::format("{} nodes", lower).c_str(), nodes.data(), nodes.size() * sizeof(nodes[0]));
      accel_[3 * s + 2] =
          ClUpload(cl_, fmt::format("{} references", lower).c_str(), data.refs.data(), data.refs.size() * sizeof(std::uint32_t));
    };
    switch (d.kind) {
#define CR_CL_UPLOAD_ACCEL(N, U, l, H, Nd) \
  case AccelKind::N: upload(CR_ACCEL_ID_##U, #l, d.l); break;
      CR_ACCEL_TYPES(CR_CL_UPLOAD_ACCEL)
#undef CR_CL_UPLOAD_ACCEL
    }
  }

  // The wide walk (kernels/bvh_wide.cl): the binary BVH collapsed into the
  // SIMD backend's 8-wide layout with triangle packs of 8 (simd/bvh_wide.h),
  // uploaded as the BVH's nodes and references in place of the binary ones.
  // References: the start of each type's packs and of the mixed leaves, then
  // the triangle, sphere and cone packs as they are (88, 40 and 80 words), each other type's packs as
  // their 8 unified ids, each mixed leaf as (first pack, packs) per type.
  void UploadWide(const AccelData& data)
  {
    static_assert(sizeof(simd::TrianglePack<8>) == 88 * sizeof(std::uint32_t));
    static_assert(sizeof(simd::SpherePack<8>) == 40 * sizeof(std::uint32_t));
    static_assert(sizeof(simd::ConePack<8>) == 80 * sizeof(std::uint32_t));
    static_assert(sizeof(simd::WideNode<8>) == 64 * sizeof(std::uint32_t));
    // kernels/bvh_wide.cl reads the shortest edge from these bits (CR_WIDE_TRI_SHORT1, 2).
    static_assert(simd::kPackShortEdge1 == 0x100u && simd::kPackShortEdge2 == 0x200u);
    const auto t0 = std::chrono::steady_clock::now();
    simd::SimdPrimData rows(scene_);
    simd::KernelScene sc;
    rows.Bind(sc);
    const std::unique_ptr<simd::WideBVHBase> base = simd::BuildWideBVH(data.bvh, sc, 8, 8);
    const auto& w = dynamic_cast<const simd::WideBVH<8, 8>&>(*base);
    std::vector<std::uint32_t> refs(CR_NUM_PRIM_TYPES + 1, 0u);
    const auto place = [&](std::uint32_t k, const auto& packs) {
      refs[k] = static_cast<std::uint32_t>(refs.size());
      if (k == CR_PRIM_TRIANGLE || k == CR_PRIM_SPHERE || k == CR_PRIM_CONE) {
        const auto* words = reinterpret_cast<const std::uint32_t*>(packs.data());
        refs.insert(refs.end(), words, words + packs.size() * (sizeof(packs[0]) / sizeof(std::uint32_t)));
      } else {
        for (const auto& p : packs) refs.insert(refs.end(), std::begin(p.g), std::end(p.g));
      }
    };
#define CR_CL_WIDE_PLACE_(T, U, a) place(CR_PRIM_##U, w.a);
    CR_PRIM_TYPES(CR_CL_WIDE_PLACE_)
#undef CR_CL_WIDE_PLACE_
    refs[CR_NUM_PRIM_TYPES] = static_cast<std::uint32_t>(refs.size());
    for (const simd::WideLeaf& leaf : w.leaves)
      for (std::uint32_t k = 0; k < CR_NUM_PRIM_TYPES; ++k) {
        refs.push_back(leaf.first[k]);
        refs.push_back(leaf.count[k]);
      }
    if (refs.size() > 0xFFFFFFFFu) throw RuntimeError("OpenCL: the wide BVH's references exceed 2^32 words");
    const std::size_t s = CR_ACCEL_ID_BVH;
    accel_[3 * s + 1] = ClUpload(cl_, "bvh wide nodes", w.nodes.data(), w.nodes.size() * sizeof(w.nodes[0]));
    accel_[3 * s + 2] = ClUpload(cl_, "bvh wide references", refs.data(), refs.size() * sizeof(std::uint32_t));
    const std::uint64_t bytes = w.nodes.size() * sizeof(w.nodes[0]) + refs.size() * sizeof(std::uint32_t);
    info_.bytes = info_.bytes - data.bvh.nodes.size() * sizeof(BVHNode) -
                  data.bvh.refs.size() * sizeof(std::uint32_t) + bytes;
    info_.params += fmt::format(" opencl=bvh8x8 wide_nodes={} wide_bytes={}", w.nodes.size(), bytes);
    info_.buildMs += MsSince(t0);
  }

  // Ray, hit and counter buffers for n rays (grown, never shrunk).
  void EnsureTimeBuffer(std::size_t n)
  {
    if (n > timeCapacity_) {
      timeBuf_ = ClAlloc(cl_, "ray times", n * sizeof(float), CL_MEM_READ_ONLY);
      timeCapacity_ = n;
    }
  }

  void EnsureRayBuffers(std::size_t n, bool withRays)
  {
    if (withRays && n > rayCapacity_) {
      rayBuf_ = ClAlloc(cl_, "rays", n * sizeof(RayRecord), CL_MEM_READ_ONLY);
      rayCapacity_ = n;
    }
    if (n > hitCapacity_) {
      hitBuf_ = ClAlloc(cl_, "hits", n * sizeof(HitRecord), CL_MEM_WRITE_ONLY);
      if (config_.stats) statsBuf_ = ClAlloc(cl_, "per-ray counters", n * kStatsBytes, CL_MEM_WRITE_ONLY);
      hitCapacity_ = n;
    }
  }

  // The hits into `hits`: read from hitBuf_, or, with `inPlace` (a buffer over hits.data() itself,
  // CL_MEM_USE_HOST_PTR), mapped and unmapped, which leaves them there (copied only where the
  // implementation kept them elsewhere).
  void ReadBack(std::size_t n, std::vector<HitRecord>& hits, TraceStatsSum* stats, cl::Buffer* inPlace = nullptr)
  {
    const std::size_t bytes = n * sizeof(HitRecord);
    if (inPlace) {
      cl_int err = CL_SUCCESS;
      void* m = cl_.queue.enqueueMapBuffer(*inPlace, CL_TRUE, CL_MAP_READ, 0, bytes, nullptr, nullptr, &err);
      CR_CL_CHECK_WHAT(err, "clEnqueueMapBuffer", "hits");
      if (m != hits.data()) std::memcpy(hits.data(), m, bytes);
      cl::Event unmapped;
      CR_CL_CHECK_WHAT(cl_.queue.enqueueUnmapMemObject(*inPlace, m, nullptr, &unmapped), "clEnqueueUnmapMemObject",
                       "hits");
      CR_CL_CHECK_WHAT(unmapped.wait(), "clWaitForEvents", "hits unmapped");
    } else {
      CR_CL_CHECK_WHAT(cl_.queue.enqueueReadBuffer(hitBuf_, CL_TRUE, 0, bytes, hits.data()), "clEnqueueReadBuffer",
                       "hits");
    }
    lastKernelMs_ = KernelMs(lastLaunch_);
    if (config_.stats && stats) {
      std::vector<std::uint32_t> per(4 * n);
      CR_CL_CHECK_WHAT(cl_.queue.enqueueReadBuffer(statsBuf_, CL_TRUE, 0, n * kStatsBytes, per.data()),
                       "clEnqueueReadBuffer", "per-ray counters");
      TraceStatsSum s;
      s.rays = n;
      for (std::size_t i = 0; i < n; ++i) {
        s.nIT += per[4 * i];
        s.nTS += per[4 * i + 1];
        s.nLeaves += per[4 * i + 2];
        s.nEmptyLeaves += per[4 * i + 3];
      }
      AddStats(*stats, s);
    }
  }

  const Scene& scene_;
  TraceConfig config_;
  ClContext cl_;
  ClVariant variant_ = ClVariant::Ray;
  // The BVH's walk: stackless (its parent links uploaded with the
  // references) or wide (its 8-wide layout uploaded instead, UploadWide).
  ClBvhWalk walk_ = ClBvhWalk::Stack;
  bool generic_ = false;
  int tileW_ = 0, tileH_ = 0;  // work-group tile (packet size)
  std::unique_ptr<Built> built_[3];  // rays closest, rays occlusion, camera (a generic program: slot 0)
  cl::Buffer dummy_, prims_[CR_NUM_PRIM_TYPES], primIds_, motion_, timeBuf_;
  std::size_t timeCapacity_ = 0;
  bool hasMotion_ = false;
  cl::Event lastLaunch_;
  double lastKernelMs_ = -1.0;
  cl::Buffer accel_[3 * CR_NUM_ACCEL_TYPES];  // per structure: header, nodes, references
  cl::Buffer rayBuf_, hitBuf_, statsBuf_;
  std::size_t rayCapacity_ = 0, hitCapacity_ = 0;
};

}  // namespace

std::unique_ptr<Tracer> CreateMultiDeviceTracer(const Scene& scene, const TraceConfig& config);  // cl_multi.cpp

std::unique_ptr<Tracer> CreateOpenCLTracer(const Scene& scene, const TraceConfig& config)
{
  if (config.device == "all" || config.device.find(',') != std::string::npos) return CreateMultiDeviceTracer(scene, config);
  return std::make_unique<ClTracer>(scene, config);
}

}  // namespace cr
