// The `simd` backend: the structures' traversals with explicit SSE4.1 /
// AVX2 kernels, chosen at run time (simd/isa.h), parallel over rays with
// oneTBB.
//
// Variants: `packet` (N coherent rays walk the structure together:
// simd/<structure>_packet.h), `single` (one ray at a time with SIMD inside
// its work: the N-wide BVH of simd/bvh_single.h, the cell walks of
// simd/<structure>_single.h with primitives tested 4 at a time), `auto` (packets when the ray set looks coherent,
// simd/ray_coherence.h, else whichever a short pilot finds faster; see
// docs/SIMD.md for the measurements behind it).
// What this backend does not implement is delegated to the scalar backend
// (the kernels of kernels/ compiled as C++), and VariantName says so:
// --isa scalar and --precision fp64. A moving scene (NFF `motion`) takes
// kernels of its own (kMotionBit, simd/motion.h); a static one never runs
// their code.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "host/core/error.h"
#include "simd/bvh_wide_builder.h"
#include "simd/isa.h"
#include "simd/ray_coherence.h"
#include "simd/ray_order.h"
#include "simd/simd_kernels.h"
#include "host/trace/tracer.h"

namespace cr {

std::unique_ptr<Tracer> CreateScalarTracer(const Scene& scene, const TraceConfig& config);

namespace simd {

namespace {

// Whether the ray-margin octree's packets search lazily (simd/octree_packet.h
// kLazy): by the tree's shape, or as $CELLRAY_OCTREE_LAZY says (on, off or
// auto: a testing and measuring aid; the answers are the same either way).
bool OctreeLazy(const OctreeData& tree)
{
  const char* env = std::getenv("CELLRAY_OCTREE_LAZY");
  const std::string how = env ? env : "";
  if (how == "on") return true;
  if (how == "off") return false;
  if (!how.empty() && how != "auto")
    throw InputError(fmt::format("CELLRAY_OCTREE_LAZY='{}': expected on, off or auto", how));
  return tree.chain >= kOctreeLazyChain;
}

enum class Variant { Auto, Packet, Single };

Variant ParseVariant(const std::string& s)
{
  if (s.empty() || s == "auto") return Variant::Auto;
  if (s == "packet") return Variant::Packet;
  if (s == "single" || s == "ray") return Variant::Single;
  throw InputError(fmt::format("--variant '{}': the simd backend has packet, single (or ray) and auto", s));
}

// A set is coherent when at least this fraction of sampled groups of
// consecutive rays share nearly one direction: packets, no question
// (primary rays measure 0.96-1.0; shadow, diffuse and random rays 0-0.02,
// and for those the pilot below decides).
constexpr double kAutoPacketFraction = 0.5;
// Incoherent sets: a pilot of 2 x 8 blocks of 512 rays (8192 rays) decides,
// when the set is large enough for the pilot to be a small part of it.
// Blocks this long keep the cache reuse of consecutive rays that the full
// run has (with 64-ray blocks the pilot favoured single rays on shadow rays
// that packets trace 1.5x faster); measurements in docs/SIMD.md.
// From 16,384 rays (a render's tile of 32 rows of 513 points casts sets
// of that size; below it such tiles all went to single rays) with fewer
// pairs, the pilot at most a quarter of the set.
constexpr std::size_t kPilotBlock = 512, kPilotBlocksEach = 8, kPilotMinRays = 16384;

struct IsaEntry {
  KernelFn (*select[CR_NUM_ACCEL_TYPES])(const KernelKey&);        // by KernelAccel
  KernelFn (*selectMotion[CR_NUM_ACCEL_TYPES])(const KernelKey&);  // a moving scene's (key.motion)
  PacketOrder (*order[CR_NUM_ACCEL_TYPES])();
  KernelProbes (*probes)();

  KernelFn Select(const KernelKey& key) const
  {
    const int a = static_cast<int>(key.accel);
    return key.motion ? selectMotion[a](key) : select[a](key);
  }
};

IsaEntry EntryOf(Isa isa)
{
#if defined(CELLRAY_SIMD_X86)
#define CR_SIMD_ENTRY_SELECT_(N, U, l, H, Nd) &ns::Select##N##Kernel,
#define CR_SIMD_ENTRY_MOTION_(N, U, l, H, Nd) &ns::SelectMotion##N##Kernel,
#define CR_SIMD_ENTRY_ORDER_(N, U, l, H, Nd) &ns::N##PacketOrder,
#define CR_SIMD_ENTRY_                                                               \
  {{CR_ACCEL_TYPES(CR_SIMD_ENTRY_SELECT_)}, {CR_ACCEL_TYPES(CR_SIMD_ENTRY_MOTION_)}, \
   {CR_ACCEL_TYPES(CR_SIMD_ENTRY_ORDER_)}, &ns::Probes}
#if defined(CELLRAY_SIMD_AVX512)
  if (isa == Isa::Avx512) {
    namespace ns = avx512;
    return CR_SIMD_ENTRY_;
  }
#endif
#if defined(CELLRAY_SIMD_AVX2)
  if (isa == Isa::Avx2) {
    namespace ns = avx2;
    return CR_SIMD_ENTRY_;
  }
#endif
#if defined(CELLRAY_SIMD_SSE4)
  if (isa == Isa::Sse4) {
    namespace ns = sse4;
    return CR_SIMD_ENTRY_;
  }
#endif
#undef CR_SIMD_ENTRY_
#undef CR_SIMD_ENTRY_ORDER_
#undef CR_SIMD_ENTRY_MOTION_
#undef CR_SIMD_ENTRY_SELECT_
#endif
  throw RuntimeError(fmt::format("simd: no kernels for isa {}", IsaName(isa)));
}

}  // namespace

KernelProbes IsaProbes(Isa isa) { return EntryOf(isa).probes(); }

namespace {

// The kernels' name for a structure (the same list, the same order).
KernelAccel KernelAccelOf(AccelKind k) { return static_cast<KernelAccel>(k); }

// The builders' parameters for this backend: on a scene of triangles only,
// the BVH's SAH counts a leaf's cost in blocks of 4 (as Embree's
// sahBlockSize for its 4-wide triangle leaves) unless --bvh-sah-block says
// otherwise. On bumpy 10^7 it made 647 MiB of 744, 2.5 s of 3.4 to build;
// with spheres and cones it cost (tree diffuse 1.6x the time), so other
// scenes keep 1 (docs/SIMD.md `single`). On a scene of triangles only, the
// octree with ray margins (the new form; the classic octree stays the
// baseline) splits leaves of more than kSimdOctreeLeaf references unless
// --octree-leaf says otherwise: this backend tests a leaf's triangles 4 at
// a time, so larger leaves and fewer of them pay (SIMD, one thread: bunny,
// igea, dragon100k, sibenik, sponza 8-55% faster than at the builder's 12);
// spheres and cones gain nothing (rings, tree 5-7% slower), and the
// OpenCL kernels, which test one at a time, lose 6% (docs/ACCEL.md).
inline constexpr int kSimdOctreeLeaf = 24;
// The scene's primitive types, a bit per CR_PRIM_* (KernelKey::types).
unsigned SceneTypes(const Scene& scene)
{
  unsigned types = 0;
  scene.ForEachType([&](const auto& pieces, std::uint32_t k) { types |= pieces.empty() ? 0u : 1u << k; });
  return types;
}

AccelParams SimdParams(const Scene& scene, const TraceConfig& cfg)
{
  AccelParams p = cfg.params;
  const bool trianglesOnly = SceneTypes(scene) == 1u << CR_PRIM_TRIANGLE;
  if (cfg.accel == AccelKind::BVH && p.bvhSahBlock == 0 && trianglesOnly) p.bvhSahBlock = 4;
  if (cfg.accel == AccelKind::Octree && p.octreeLeaf == 0 && p.octreeMargin == "ray" && p.octreeBuild != "sah" &&
      trianglesOnly)
    p.octreeLeaf = kSimdOctreeLeaf;
  return p;
}

class SimdTracer final : public Tracer {
 public:
  SimdTracer(const Scene& scene, const TraceConfig& cfg, Isa isa, Variant variant)
      : config_(cfg), isa_(isa), variant_(variant), primIds_(scene.UnifiedIds()), motion_(scene.UnifiedMotion())
  {
    data_ = BuildAccel(scene, cfg.accel, SimdParams(scene, cfg));
    info_ = data_.info;
    const IsaEntry e = EntryOf(isa);
    const KernelProbes probes = e.probes();
    width_ = probes.width;
    const auto t0 = std::chrono::steady_clock::now();
    rows_ = std::make_unique<SimdPrimData>(scene);
    rows_->Bind(sc_);
    if (cfg.accel == AccelKind::BVH) {
      // Both variants walk the wide layout; only a moving scene's packets
      // walk the binary BVH (simd/kernels_motion_bvh.cpp), so a static
      // scene's binary BVH is freed once collapsed.
      wide_ = BuildWideBVH(data_.bvh, sc_, probes.width, probes.packWidth);
      info_.bytes += wide_->Bytes();
      info_.params += fmt::format(" simd=bvh{}x{} wide_nodes={} wide_bytes={}", probes.width, probes.packWidth,
                                  wide_->Nodes(), wide_->Bytes());
      if (motion_.empty()) {
        info_.bytes -= data_.bvh.nodes.size() * sizeof(BVHNode) + data_.bvh.refs.size() * sizeof(std::uint32_t);
        info_.params += " binary=freed";
        decltype(data_.bvh.nodes)().swap(data_.bvh.nodes);
        decltype(data_.bvh.refs)().swap(data_.bvh.refs);
      }
    }
    info_.bytes += rows_->Bytes();
    info_.buildMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

#define CR_SIMD_BIND_ACCEL_(N, U, l, H, Nd) \
  sc_.l##Header = &data_.l.header;          \
  sc_.l##Nodes = data_.l.Nodes().data();    \
  sc_.l##Refs = data_.l.refs.data();
    CR_ACCEL_TYPES(CR_SIMD_BIND_ACCEL_)
#undef CR_SIMD_BIND_ACCEL_
    if (wide_) wide_->Bind(sc_);
    sc_.primIds = primIds_.data();
    sc_.unifiedHits = cfg.unifiedHits ? 1 : 0;
    if (cfg.accel == AccelKind::Octree && (data_.octree.header.flags & CR_OCTREE_MARGIN_RAY))
      sc_.octreeLazy = OctreeLazy(data_.octree) ? 1 : 0;
    sc_.motion = motion_.empty() ? nullptr : motion_.data();

    KernelKey key;
    key.accel = KernelAccelOf(cfg.accel);
    key.types = SceneTypes(scene);
    key.fast = cfg.precision == Precision::Fast;
    key.stats = cfg.stats;
    key.motion = sc_.motion != nullptr;
    key.packet = true;
    packetFn_ = e.Select(key);
    packetOrder_ = e.order[static_cast<int>(key.accel)]();
    key.packet = false;
    singleFn_ = e.Select(key);
  }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    hits.resize(rays.size());
    traced_ = true;
    if (!times.empty() && times.size() != rays.size())
      throw RuntimeError(fmt::format("simd: {} ray times for {} rays", times.size(), rays.size()));
    // Times matter to a moving scene's kernels only.
    const float* rayTimes = sc_.motion && !times.empty() ? times.data() : nullptr;
    const bool wantStats = config_.stats && stats;
    TraceStatsSum sum;
    if (!packetFn_) {
      // No primitives: every ray misses.
      for (auto& h : hits) h = HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f};
      sum.rays = rays.size();
    } else {
      // order: the positions still to trace (all rays when empty).
      std::vector<std::uint32_t> order;
      const bool mayPack = variant_ != Variant::Single;
      const bool classes = packetOrder_ != PacketOrder::Input;
      const bool coherent = (variant_ == Variant::Auto || (mayPack && classes)) &&
                            SampleCoherence(rays, width_).Fraction() >= kAutoPacketFraction;
      // packetOrder: the positions to form packets from, in order (empty: the
      // rays in input order). The packets of an incoherent set are formed per
      // direction class where the structure's kernels ask for it
      // (PacketOrder; DirectionClassOrder says why), the pilot's included.
      std::vector<std::uint32_t> packetOrder;
      if (mayPack && !coherent &&
          (packetOrder_ == PacketOrder::DirectionClasses ||
           (packetOrder_ == PacketOrder::DirectionClassesWhenPays && GridClassOrderPays(rays))))
        packetOrder = DirectionClassOrder(rays);
      if (variant_ == Variant::Packet)
        usedPacket_ = true;
      else if (variant_ == Variant::Single)
        usedPacket_ = false;
      else if (coherent)
        usedPacket_ = true;
      else if (rays.size() < kPilotMinRays)
        usedPacket_ = false;
      else
        usedPacket_ = Pilot(rays, rayTimes, hits, occlusion, wantStats ? &sum : nullptr, packetOrder, order);
      if (usedPacket_ && order.empty() && !packetOrder.empty()) order = std::move(packetOrder);
      std::uint32_t imageWidth = 0;
      if (usedPacket_ && order.empty()) {
        // Packets of primary rays cover compact image tiles (4x2 or 2x2
        // pixels) rather than row segments when the set is a row-major
        // image: computed in the kernel when the tiles fit the image, else
        // through an order.
        const int w = DetectImageWidth(rays);
        const std::size_t tileW = std::size_t(width_) / 2;
        if (w > 0 && std::size_t(w) % tileW == 0 && (rays.size() / std::size_t(w)) % 2 == 0)
          imageWidth = static_cast<std::uint32_t>(w);
        else if (w > 0)
          order = TileOrder(rays.size(), w, int(tileW), 2);
      }
      Run(usedPacket_ ? packetFn_ : singleFn_, usedPacket_, rays, rayTimes, hits, order, imageWidth, occlusion,
          wantStats ? &sum : nullptr);
    }
    if (wantStats) {
      stats->rays += sum.rays;
      stats->nIT += sum.nIT;
      stats->nTS += sum.nTS;
      stats->nLeaves += sum.nLeaves;
      stats->nEmptyLeaves += sum.nEmptyLeaves;
    }
  }

  std::string DeviceName() const override { return "cpu"; }
  std::string VariantName() const override
  {
    std::string v = usedPacket_ ? "packet" : "single";
    if (variant_ == Variant::Auto && !traced_) v = "auto";
    return fmt::format("{} {}{}", IsaName(isa_), v, config_.precision == Precision::Fast ? " fast" : "");
  }

 private:
  TraceConfig config_;
  Isa isa_;
  Variant variant_;
  AccelData data_;
  std::vector<std::uint32_t> primIds_;
  std::vector<float> motion_;  // Scene::UnifiedMotion, empty for a static scene
  std::unique_ptr<SimdPrimData> rows_;
  std::unique_ptr<WideBVHBase> wide_;
  KernelScene sc_;
  KernelFn packetFn_ = nullptr, singleFn_ = nullptr;
  PacketOrder packetOrder_ = PacketOrder::Input;
  int width_ = 4;
  bool usedPacket_ = false;
  bool traced_ = false;

  // Traces positions [0, n) of `order`, or when order is empty of the rays
  // themselves (in image tiles when imageWidth > 0, KernelJob), parallel over
  // blocks of whole packets: small enough to balance the threads, large
  // enough to amortise the scheduling. times: per ray, or null (KernelJob).
  void Run(KernelFn fn, bool packet, RaySpan rays, const float* times,
           std::vector<HitRecord>& hits, const std::vector<std::uint32_t>& order, std::uint32_t imageWidth,
           bool occlusion, TraceStatsSum* sum) const
  {
    const std::size_t n = order.empty() ? rays.size() : order.size();
    const std::size_t unit = packet ? std::size_t(width_) : 1;
    const std::size_t nUnits = (n + unit - 1) / unit;
    const std::size_t grain = packet ? 16 : 64;
    tbb::enumerable_thread_specific<TraceStatsSum> local;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nUnits, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      KernelJob job;
      job.rays = rays.data();
      job.times = times;
      job.hits = hits.data();
      job.order = order.empty() ? nullptr : order.data();
      job.imageWidth = imageWidth;
      job.begin = r.begin() * unit;
      job.end = std::min(r.end() * unit, n);
      job.occlusion = occlusion ? 1 : 0;
      job.stats = sum ? &local.local() : nullptr;
      fn(sc_, job);
    });
    if (sum) {
      for (const TraceStatsSum& s : local) AddStats(*sum, s);
    }
  }

  // Grid packets of an incoherent set: input order or direction class
  // order? A packet's lanes share work in the cells they stand in together.
  // Rays that walk only a few cells share most where they start together,
  // and the input order keeps rays from one surface point (towards several
  // lights) and from neighbouring points together; rays that walk many
  // cells share most when they also go the same way, which the class order
  // adds. Measured (docs/SIMD.md, one thread): input order 27% faster on
  // gears shadow rays (2.3 cells a ray) and 6-18% on diffuse rays, class
  // order 12-33% faster on balls, teapot and tree shadow rays (21 cells a
  // ray on balls). So: class order when most rays are finite segments whose
  // part inside the grid box spans at least kLongWalkCells cells on average
  // (a sample of the set; planes crossed plus one), else input order.
  static constexpr double kLongWalkCells = 8.0;
  bool GridClassOrderPays(RaySpan rays) const
  {
    const GridHeader& g = data_.grid.header;
    const std::size_t n = rays.size(), step = std::max<std::size_t>(1, n / 2048);
    std::size_t sampled = 0, finite = 0, inside = 0;
    double cells = 0.0;
    for (std::size_t i = 0; i < n; i += step) {
      ++sampled;
      const RayRecord& r = rays[i];
      if (!std::isfinite(r.tmax)) continue;
      ++finite;
      double t0 = r.tmin, t1 = r.tmax;
      for (int a = 0; a < 3 && t0 <= t1; ++a) {
        if (r.dir[a] == 0.0f) {
          if (r.org[a] < g.bmin[a] || r.org[a] > g.bmax[a]) t1 = -1.0;
          continue;
        }
        const double inv = 1.0 / double(r.dir[a]);
        double ta = (double(g.bmin[a]) - r.org[a]) * inv, tb = (double(g.bmax[a]) - r.org[a]) * inv;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (!(t0 <= t1)) continue;
      ++inside;
      double span = 1.0;
      for (int a = 0; a < 3; ++a) span += std::fabs(double(r.dir[a])) * (t1 - t0) / double(g.cellSize[a]);
      cells += span;
    }
    return 2 * finite >= sampled && inside > 0 && cells >= kLongWalkCells * double(inside);
  }

  // `auto` on an incoherent ray set decides by measurement: blocks of rays
  // spread over the whole set are traced alternately with packets and one
  // ray at a time (for real: their answers are kept), and the variant that
  // took less time traces the rest, whose positions go to `rest`. Which
  // variant wins depends on the scene as much as on the rays (docs/SIMD.md:
  // on random rays packets win on balls and tree, single rays on gears and
  // teapot), so no ray-set statistic predicts it as well.
  bool Pilot(RaySpan rays, const float* times, std::vector<HitRecord>& hits, bool occlusion,
             TraceStatsSum* sum, const std::vector<std::uint32_t>& seq, std::vector<std::uint32_t>& rest) const
  {
    // seq: the positions in the order to trace them (the rays themselves when empty).
    const std::size_t n = seq.empty() ? rays.size() : seq.size();
    const std::size_t nBlocks = n / kPilotBlock;
    // Pairs of adjacent blocks (one packet, one single: rays of the same kind
    // and, in a class order, of the same class) spread over the sequence.
    const std::size_t nPairs = std::min<std::size_t>(kPilotBlocksEach, nBlocks / 8);
    const std::size_t nPilot = 2 * nPairs;
    const std::size_t stride = nBlocks / nPairs;
    std::vector<char> isPilot(nBlocks, 0);
    for (std::size_t i = 0; i < nPilot; ++i) isPilot[(i / 2) * stride + (i & 1)] = 1;
    // The blocks run on all threads, each timed on its own (a serial pilot
    // was an eighth of a 65,536-ray set on one thread while the others
    // waited); both variants' blocks meet the same contention.
    std::vector<double> blockSeconds(nPilot, 0.0);
    tbb::enumerable_thread_specific<TraceStatsSum> local;
    tbb::parallel_for(std::size_t(0), nPilot, [&](std::size_t i) {
      const std::size_t b = (i / 2) * stride + (i & 1);
      KernelJob job;
      job.rays = rays.data();
      job.times = times;
      job.hits = hits.data();
      job.order = seq.empty() ? nullptr : seq.data();
      job.begin = b * kPilotBlock;
      job.end = job.begin + kPilotBlock;
      job.occlusion = occlusion ? 1 : 0;
      job.stats = sum ? &local.local() : nullptr;
      const int single = static_cast<int>(i & 1);
      const auto t0 = std::chrono::steady_clock::now();
      (single ? singleFn_ : packetFn_)(sc_, job);
      blockSeconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
    double seconds[2] = {0.0, 0.0};
    for (std::size_t i = 0; i < nPilot; ++i) seconds[i & 1] += blockSeconds[i];
    if (sum)
      for (const TraceStatsSum& s : local) AddStats(*sum, s);
    rest.clear();
    rest.reserve(n - nPilot * kPilotBlock);
    for (std::size_t p = 0; p < n; ++p)
      if (p / kPilotBlock >= nBlocks || !isPilot[p / kPilotBlock])
        rest.push_back(seq.empty() ? static_cast<std::uint32_t>(p) : seq[p]);
    return seconds[0] <= seconds[1];
  }
};

// What the SIMD backend hands to the scalar one, named in VariantName.
class DelegatingTracer final : public Tracer {
 public:
  DelegatingTracer(std::unique_ptr<Tracer> inner, std::string why) : inner_(std::move(inner)), why_(std::move(why))
  {
    info_ = inner_->Info();
  }
  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    TraceInRange(*inner_, rays, times, hits, occlusion, stats);
  }
  std::string DeviceName() const override { return inner_->DeviceName(); }
  std::string VariantName() const override { return fmt::format("scalar ray ({})", why_); }

 private:
  std::unique_ptr<Tracer> inner_;
  std::string why_;
};

}  // namespace

}  // namespace simd

namespace {

// Why this configuration runs on the scalar backend instead; empty when
// the SIMD kernels run it.
std::string WhyDelegated(const TraceConfig& config, simd::Isa isa)
{
  if (isa == simd::Isa::Scalar) return config.isa.empty() ? "no SIMD ISA on this CPU" : "--isa scalar";
  if (config.precision == Precision::Fp64) return "fp64 delegated";
  return {};
}

}  // namespace

namespace simd {
AccelParams SimdTracerParams(const Scene& scene, const TraceConfig& config)
{
  return WhyDelegated(config, ParseIsa(config.isa)).empty() ? SimdParams(scene, config) : config.params;
}
AccelParams WideLayoutParams(const Scene& scene, const TraceConfig& config) { return SimdParams(scene, config); }
}  // namespace simd

std::unique_ptr<Tracer> CreateSimdTracer(const Scene& scene, const TraceConfig& config)
{
  using namespace simd;
  const Isa isa = ParseIsa(config.isa);
  const Variant variant = ParseVariant(config.variant);
  const std::string why = WhyDelegated(config, isa);
  if (!why.empty()) return std::make_unique<DelegatingTracer>(CreateScalarTracer(scene, config), why);
  return std::make_unique<SimdTracer>(scene, config, isa, variant);
}

}  // namespace cr
