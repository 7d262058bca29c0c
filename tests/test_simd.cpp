// The SIMD backend against the fp64 reference and against the scalar
// backend: every SPD scene x ray kind x ISA this CPU has x variant, 0 wrong,
// and the scalar backend's primitive ids (closest hits: the same t to 2 ulp;
// only exact ties may name another primitive, and they are counted).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include <tbb/task_arena.h>

#include "host/core/error.h"
#include "host/scene/generate.h"
#include "simd/bvh_wide_builder.h"
#include "simd/isa.h"
#include "simd/ray_order.h"
#include "tests/test_util.h"

using namespace cr;
using cr::test::kKinds;
using cr::test::UlpDistance;

namespace {

constexpr auto& kSimdAccels = kAccelKinds;
const char* const kVariants[] = {"packet", "single"};

std::vector<std::string> AvailableIsas() { return simd::SupportedVectorIsas(); }

struct SimdComparison {
  std::uint64_t differentPrim = 0;     // closest hit: other primitive, t not equal (a failure)
  std::uint64_t exactTies = 0;         // closest hit: other primitive at exactly the same t
  std::uint64_t tBeyond2Ulp = 0;       // same primitive, t more than 2 ulp apart (a failure)
  std::uint64_t otherOccluder = 0;     // occlusion: both occluded, another occluder (allowed)
  std::uint64_t occlusionDiffers = 0;  // occlusion: occluded vs free (a failure)
  std::uint64_t firstBad = ~0ull;
};

SimdComparison CompareWithScalar(const std::vector<HitRecord>& scalar, const std::vector<HitRecord>& simd, bool occlusion)
{
  SimdComparison c;
  REQUIRE(scalar.size() == simd.size());
  for (std::size_t i = 0; i < scalar.size(); ++i) {
    const HitRecord& a = scalar[i];
    const HitRecord& b = simd[i];
    bool bad = false;
    if (occlusion) {
      if ((a.prim == CR_NO_HIT) != (b.prim == CR_NO_HIT))
        bad = true, ++c.occlusionDiffers;
      else if (a.prim != b.prim)
        ++c.otherOccluder;
    } else if (a.prim != b.prim) {
      if (a.t == b.t)
        ++c.exactTies;
      else
        bad = true, ++c.differentPrim;
    } else if (a.prim != CR_NO_HIT && UlpDistance(a.t, b.t) > 2) {
      bad = true, ++c.tBeyond2Ulp;
    }
    if (bad && c.firstBad == ~0ull) c.firstBad = i;
  }
  return c;
}

std::vector<HitRecord> TraceWith(const Scene& scene, const TraceConfig& cfg, const std::vector<RayRecord>& rays,
                                 bool occlusion, std::string* variantName = nullptr)
{
  auto tracer = CreateTracer(scene, cfg);
  std::vector<HitRecord> hits;
  tracer->Trace(rays, hits, occlusion, nullptr);
  if (variantName) *variantName = tracer->VariantName();
  return hits;
}

}  // namespace

TEST_CASE("simd: every SPD scene x ray kind x ISA x variant matches the reference and the scalar backend")
{
  const auto isas = AvailableIsas();
  if (isas.empty()) {
    MESSAGE("SKIPPED: this CPU has neither SSE4.1 nor AVX2; the simd backend runs its scalar fallback only");
    return;
  }
  constexpr std::size_t kAccels = std::size(kAccelKinds);
  std::uint64_t totalTies[kAccels] = {}, totalOtherOccluders[kAccels] = {}, totalRays[kAccels] = {};
  for (const std::string& name : test::SpdScenes()) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    for (RayKind kind : kKinds) {
      const auto rays = test::MakeRays(scene, kind, 40);
      const bool occlusion = test::IsOcclusion(kind);
      for (AccelKind accel : kSimdAccels) {
        TraceConfig scalarCfg;
        scalarCfg.backend = Backend::Scalar;
        scalarCfg.accel = accel;
        const auto scalarHits = TraceWith(scene, scalarCfg, rays, occlusion);
        for (const std::string& isa : isas) {
          for (const char* variant : kVariants) {
            TraceConfig cfg;
            cfg.backend = Backend::Simd;
            cfg.accel = accel;
            cfg.isa = isa;
            cfg.variant = variant;
            std::vector<HitRecord> hits;
            const auto r = test::CheckTracer(scene, cfg, rays, occlusion, &hits);
            const SimdComparison c = CompareWithScalar(scalarHits, hits, occlusion);
            INFO(name, " ", RayKindName(kind), " ", AccelKindName(accel), " ", isa, " ", variant, ": ", r.wrong,
                 " wrong of ", r.rays, "; vs scalar: ", c.differentPrim, " other prim, ", c.tBeyond2Ulp, " t > 2 ulp, ",
                 c.occlusionDiffers, " occlusion differs (first ray ", c.firstBad, ")");
            CHECK(r.rays == rays.size());
            CHECK(r.wrong == 0);
            CHECK(c.differentPrim == 0);
            CHECK(c.tBeyond2Ulp == 0);
            CHECK(c.occlusionDiffers == 0);
            const int ai = static_cast<int>(accel);
            totalTies[ai] += c.exactTies;
            totalOtherOccluders[ai] += c.otherOccluder;
            totalRays[ai] += rays.size();
          }
        }
      }
    }
  }
  for (AccelKind accel : kSimdAccels) {
    const int ai = static_cast<int>(accel);
    MESSAGE("simd vs scalar, ", std::string(AccelKindName(accel)), ", over ", totalRays[ai], " rays: ", totalTies[ai],
            " exact ties named another primitive, ", totalOtherOccluders[ai],
            " occlusion queries named another occluder");
  }
}

TEST_CASE("simd: fast precision returns the scalar fast kernels' answers")
{
  const auto isas = AvailableIsas();
  if (isas.empty()) return;
  for (const std::string& name : test::Scenes({"balls", "gears", "tree", "lattice"})) {
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    for (RayKind kind : {RayKind::Primary, RayKind::Shadow, RayKind::Random}) {
      const auto rays = test::MakeRays(scene, kind, 32);
      const bool occlusion = test::IsOcclusion(kind);
      for (AccelKind accel : kSimdAccels) {
        TraceConfig scalarCfg;
        scalarCfg.backend = Backend::Scalar;
        scalarCfg.accel = accel;
        scalarCfg.precision = Precision::Fast;
        const auto scalarHits = TraceWith(scene, scalarCfg, rays, occlusion);
        for (const std::string& isa : isas) {
          for (const char* variant : kVariants) {
            TraceConfig cfg = scalarCfg;
            cfg.backend = Backend::Simd;
            cfg.isa = isa;
            cfg.variant = variant;
            std::string vn;
            const auto hits = TraceWith(scene, cfg, rays, occlusion, &vn);
            const SimdComparison c = CompareWithScalar(scalarHits, hits, occlusion);
            INFO(name, " ", RayKindName(kind), " ", AccelKindName(accel), " ", vn);
            CHECK(vn == isa + " " + variant + " fast");
            CHECK(c.differentPrim == 0);
            CHECK(c.tBeyond2Ulp == 0);
            CHECK(c.occlusionDiffers == 0);
          }
        }
      }
    }
  }
}

TEST_CASE("simd: unified hits, statistics and the auto variant")
{
  const auto isas = AvailableIsas();
  if (isas.empty()) return;
  const Scene& scene = test::CachedScene(test::SpdPath("teapot"));
  const auto primary = test::MakeRays(scene, RayKind::Primary, 48);
  const auto random = test::MakeRays(scene, RayKind::Random, 48);

  TraceConfig scalarCfg;
  scalarCfg.backend = Backend::Scalar;
  scalarCfg.unifiedHits = true;
  scalarCfg.stats = true;
  const auto scalarHits = TraceWith(scene, scalarCfg, primary, false);

  for (const std::string& isa : isas) {
    for (const char* variant : kVariants) {
      TraceConfig cfg = scalarCfg;
      cfg.backend = Backend::Simd;
      cfg.isa = isa;
      cfg.variant = variant;
      auto tracer = CreateTracer(scene, cfg);
      std::vector<HitRecord> hits;
      TraceStatsSum st;
      tracer->Trace(primary, hits, false, &st);
      INFO(isa, " ", variant);
      // Unified form: piece index and barycentrics of every triangle piece, bit for bit.
      REQUIRE(hits.size() == scalarHits.size());
      std::size_t same = 0;
      for (std::size_t i = 0; i < hits.size(); ++i)
        same += std::memcmp(&hits[i], &scalarHits[i], sizeof(HitRecord)) == 0;
      CHECK(same == hits.size());
      CHECK(st.rays == primary.size());
      CHECK(st.nTS >= st.rays / 2);
      CHECK(st.nIT > 0);
      CHECK(st.nLeaves > 0);
      CHECK(st.nLeaves <= st.nTS);
      CHECK(st.nEmptyLeaves == 0);
    }
    TraceConfig cfg;
    cfg.backend = Backend::Simd;
    cfg.isa = isa;
    std::string vn;
    TraceWith(scene, cfg, primary, false, &vn);
    CHECK(vn == isa + " packet");
    TraceWith(scene, cfg, random, false, &vn);
    CHECK(vn == isa + " single");
  }
}

TEST_CASE("simd: ISA and variant selection, delegation and errors")
{
  const Scene& scene = test::CachedScene(test::SpdPath("jacks"));
  TraceConfig cfg;
  cfg.backend = Backend::Simd;
  cfg.isa = "neon";
  CHECK_THROWS_AS(CreateTracer(scene, cfg), InputError);
  cfg.isa = "";
  cfg.variant = "sideways";
  CHECK_THROWS_AS(CreateTracer(scene, cfg), InputError);
  cfg.variant = "";
  for (const simd::Isa want : {simd::Isa::Sse4, simd::Isa::Avx2, simd::Isa::Avx512}) {
    cfg.isa = simd::IsaName(want);
    const bool supported = simd::IsaSupported(want);
    if (supported)
      CHECK_NOTHROW(CreateTracer(scene, cfg));
    else
      CHECK_THROWS_AS(CreateTracer(scene, cfg), InputError);
  }
  // What the SIMD backend hands to the scalar one is named.
  cfg.isa = "scalar";
  CHECK(CreateTracer(scene, cfg)->VariantName() == "scalar ray (--isa scalar)");
  cfg.isa = "";
  cfg.precision = Precision::Fp64;
  CHECK(CreateTracer(scene, cfg)->VariantName() == "scalar ray (fp64 delegated)");
}

TEST_CASE("simd: a scene without primitives answers misses")
{
  Scene scene;
  ParseNFF("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.1\nresolution 8 8\n", "empty.nff", scene);
  REQUIRE(scene.NumUnified() == 0);
  std::vector<RayRecord> rays(13, RayRecord{{0.0f, 0.0f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY});
  for (const std::string& isa : AvailableIsas()) {
    for (const char* variant : kVariants) {
      TraceConfig cfg;
      cfg.backend = Backend::Simd;
      cfg.isa = isa;
      cfg.variant = variant;
      for (bool occlusion : {false, true}) {
        const auto hits = TraceWith(scene, cfg, rays, occlusion);
        REQUIRE(hits.size() == rays.size());
        for (const HitRecord& h : hits) {
          CHECK(h.prim == CR_NO_HIT);
          CHECK(std::isinf(h.t));
        }
      }
    }
  }
}

TEST_CASE("simd: packet formation finds the image of primary rays and tiles it")
{
  const Scene& scene = test::CachedScene(test::SpdPath("gears"));
  RayGenOptions g;
  g.kind = RayKind::Primary;
  g.width = 24;
  g.height = 10;
  const auto primary = GenerateRays(scene, test::CachedReference(scene), g);
  CHECK(simd::DetectImageWidth(primary) == 24);
  CHECK(simd::DetectImageWidth(test::MakeRays(scene, RayKind::Diffuse, 16)) == 0);
  CHECK(simd::DetectImageWidth(test::MakeRays(scene, RayKind::Random, 16)) == 0);
  const auto order = simd::TileOrder(primary.size(), 24, 4, 2);
  REQUIRE(order.size() == primary.size());
  // A permutation whose first packet is the 4x2 tile at the top left.
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) CHECK(sorted[i] == i);
  const std::uint32_t firstTile[8] = {0, 1, 2, 3, 24, 25, 26, 27};
  for (int i = 0; i < 8; ++i) CHECK(order[std::size_t(i)] == firstTile[i]);
}

TEST_CASE("simd: auto on a large incoherent set (pilot blocks, then the rest) answers every ray once")
{
  const auto isas = AvailableIsas();
  if (isas.empty()) return;
  const Scene& scene = test::CachedScene(test::SpdPath("balls"));
  const auto rays = test::MakeRays(scene, RayKind::Diffuse, 260);  // 67600 rays: above the pilot threshold
  TraceConfig scalarCfg;
  scalarCfg.backend = Backend::Scalar;
  const auto scalarHits = TraceWith(scene, scalarCfg, rays, false);
  for (const std::string& isa : isas) {
    TraceConfig cfg;
    cfg.backend = Backend::Simd;
    cfg.isa = isa;
    cfg.stats = true;
    auto tracer = CreateTracer(scene, cfg);
    std::vector<HitRecord> hits(rays.size(), HitRecord{-1.0f, 12345u, -1.0f, -1.0f});
    TraceStatsSum st;
    tracer->Trace(rays, hits, false, &st);
    INFO(isa, " ", tracer->VariantName());
    CHECK((tracer->VariantName() == isa + " packet" || tracer->VariantName() == isa + " single"));
    CHECK(st.rays == rays.size());
    std::size_t same = 0;
    for (std::size_t i = 0; i < hits.size(); ++i) same += std::memcmp(&hits[i], &scalarHits[i], sizeof(HitRecord)) == 0;
    CHECK(same == rays.size());
  }
}

// The builders place work on threads (the binary BVH's flat subtrees, the
// wide collapse's top subtrees) but not the results: the binary BVH and its
// 8-wide layout are the same on 1 and 2 threads, node for node and pack for
// pack (a bumpy mesh of 10^5 triangles: binary subtrees above 4,096
// references, wide levels written in parallel; and tree, of several types).
TEST_CASE("simd: the BVH and its wide layout do not depend on the thread count")
{
  const Scene bumpy = GenerateBumpySphere(100000);
  const Scene& tree = test::CachedScene(test::SpdPath("tree"));
  for (const Scene* scene : {&bumpy, &tree}) {
    CAPTURE(scene->NumUnified());
    struct Built {
      AccelData data;
      std::unique_ptr<simd::WideBVHBase> wide;
    };
    simd::KernelScene sc;
    simd::SimdPrimData rows(*scene);
    rows.Bind(sc);
    auto build = [&](int threads) {
      Built b;
      tbb::task_arena(threads).execute([&] {
        b.data = BuildAccel(*scene, AccelKind::BVH, AccelParams{});
        b.wide = simd::BuildWideBVH(b.data.bvh, sc, 8, 4);
      });
      return b;
    };
    const Built one = build(1), two = build(2);
    const BVHData& x = one.data.bvh;
    const BVHData& y = two.data.bvh;
    REQUIRE(x.nodes.size() == y.nodes.size());
    CHECK(std::memcmp(x.nodes.data(), y.nodes.data(), x.nodes.size() * sizeof(BVHNode)) == 0);
    CHECK(std::equal(x.refs.begin(), x.refs.end(), y.refs.begin(), y.refs.end()));
    const auto& wx = dynamic_cast<const simd::WideBVH<8, 4>&>(*one.wide);
    const auto& wy = dynamic_cast<const simd::WideBVH<8, 4>&>(*two.wide);
    REQUIRE(wx.nodes.size() == wy.nodes.size());
    CHECK(wx.nodes.size() > 64);  // deeper than the levels written in parallel
    CHECK(std::memcmp(wx.nodes.data(), wy.nodes.data(), wx.nodes.size() * sizeof(simd::WideNode<8>)) == 0);
    REQUIRE(wx.leaves.size() == wy.leaves.size());
    for (std::size_t i = 0; i < wx.leaves.size(); ++i)
      for (std::uint32_t t = 0; t < CR_NUM_PRIM_TYPES; ++t) {
        CHECK(wx.leaves[i].first[t] == wy.leaves[i].first[t]);
        CHECK(wx.leaves[i].count[t] == wy.leaves[i].count[t]);
      }
#define CR_TEST_PACKS_(T, U, a)                                                            \
  REQUIRE(wx.a.size() == wy.a.size());                                                     \
  for (std::size_t i = 0; i < wx.a.size(); ++i)                                            \
    CHECK(std::memcmp(wx.a[i].g, wy.a[i].g, sizeof(wx.a[i].g)) == 0);
    CR_PRIM_TYPES(CR_TEST_PACKS_)
#undef CR_TEST_PACKS_
  }
}

// The wide layout (simd/bvh_wide.h) as the single-ray kernels read it: every
// reference of the binary BVH in exactly one pack slot reached from the
// root, a one-type slot's packs of that type, and the collapse's merged
// leaves filling the packs (the binary leaves alone average under 2 of 4).
TEST_CASE("simd: the wide BVH holds every reference once, in packs the slots name")
{
  for (const char* name : {"tetra", "mount", "tree", "gears"}) {
    CAPTURE(name);
    const Scene& scene = test::CachedScene(test::SpdPath(name));
    const AccelData data = BuildAccel(scene, AccelKind::BVH, AccelParams{});
    simd::KernelScene sc;
    simd::SimdPrimData rows(scene);
    rows.Bind(sc);
    for (const auto& nk : {std::pair{8, 4}, std::pair{4, 4}}) {
      const int n = nk.first, k = nk.second;  // not a binding: clang 14 cannot capture one
      CAPTURE(n);
      const auto wide = simd::BuildWideBVH(data.bvh, sc, n, k);
      wide->Bind(sc);
      std::vector<std::uint32_t> seen;
      std::size_t slots = 0;
      // Packs of type t from p, c of them: their valid lanes.
      auto packs = [&](std::uint32_t t, std::uint32_t p, std::uint32_t c) {
        scene.ForEachType([&](const auto& pieces, std::uint32_t type) {
          using T = typename std::decay_t<decltype(pieces)>::value_type;
          if (type != t) return;
          const auto* pk = static_cast<const typename simd::SimdPrim<T>::template Pack<4>*>(sc.packs[t]) + p;
          for (std::uint32_t i = 0; i < c; ++i)
            for (int l = 0; l < 4; ++l) {
              ++slots;
              if (pk[i].g[l] == CR_NO_HIT) continue;
              CHECK(Prim_Is(&sc.ranges, t, pk[i].g[l]));
              seen.push_back(pk[i].g[l]);
            }
        });
      };
      std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{0u, 0u}};
      while (!stack.empty()) {
        const auto [child, meta] = stack.back();
        stack.pop_back();
        if (!(child & simd::kWideLeafFlag)) {
          for (int i = 0; i < n; ++i) {
            const std::uint32_t c = n == 8 ? static_cast<const simd::WideNode<8>*>(sc.wideNodes)[child].child[i]
                                           : static_cast<const simd::WideNode<4>*>(sc.wideNodes)[child].child[i];
            const std::uint32_t m = n == 8 ? static_cast<const simd::WideNode<8>*>(sc.wideNodes)[child].meta[i]
                                           : static_cast<const simd::WideNode<4>*>(sc.wideNodes)[child].meta[i];
            CHECK((m == 0) == !(c & simd::kWideLeafFlag));
            stack.push_back({c, m});
          }
          continue;
        }
        const std::uint32_t p = child & ~simd::kWideLeafFlag;
        if (meta != simd::kWideMixedLeaf) {
          CHECK((meta & 0xffffu) > 0u);
          packs((meta >> 16) - 1u, p, meta & 0xffffu);
          continue;
        }
        const simd::WideLeaf& leaf = sc.wideLeaves[p];
        for (std::uint32_t t = 0; t < CR_NUM_PRIM_TYPES; ++t) packs(t, leaf.first[t], leaf.count[t]);
      }
      std::vector<std::uint32_t> refs(data.bvh.refs.begin(), data.bvh.refs.end());
      std::sort(refs.begin(), refs.end());
      std::sort(seen.begin(), seen.end());
      CHECK(seen == refs);
      // The binary leaves as they were, each type in its own packs: merging
      // never takes more slots, and takes fewer wherever leaves were small.
      std::size_t binarySlots = 0;
      for (const BVHNode& b : data.bvh.nodes) {
        if (b.count == 0) continue;
        std::uint32_t per[CR_NUM_PRIM_TYPES] = {};
        for (std::uint32_t i = b.first; i < b.first + b.count; ++i)
          for (std::uint32_t t = 0; t < CR_NUM_PRIM_TYPES; ++t)
            if (Prim_Is(&sc.ranges, t, data.bvh.refs[i])) ++per[t];
        for (std::uint32_t m : per) binarySlots += 4 * ((m + 3) / 4);
      }
      MESSAGE(std::string(name) << " bvh" << n << "x4: " << seen.size() << " refs in " << slots
                                << " pack slots (binary leaves: " << binarySlots << ")");
      CHECK(slots <= binarySlots);
      if (binarySlots > refs.size()) CHECK(slots < binarySlots);
    }
  }
}
