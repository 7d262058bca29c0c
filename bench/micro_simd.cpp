// The SIMD intersectors (simd/intersect_simd.h) through the probes each ISA
// unit exports (simd/simd_kernels.h KernelProbes): the packet form (N rays
// against one primitive or box) and the single-ray form (one ray against a
// pack of K primitives or N boxes). A probe call prepares its rays, so
// compare with the scalar "WithSetup" benchmarks. Items: ray-primitive (or
// ray-box) tests. Validated before timing: the middle ray hits at the known
// distance in every lane, and both forms find the same number of hits.
#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "bench/micro_common.h"
#include "simd/probe_scene.h"
#include "simd/isa.h"
#include "simd/simd_kernels.h"

namespace cr::micro {

namespace {

using simd::KernelProbes;
using simd::ProbeResult;

constexpr int kRays = 1024;

// One primitive of each type at the origin (the scalar benchmarks' shapes).
struct MicroScene : simd::ProbeScene {
  MicroScene()
  {
    scene.spheres.push_back(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f});
    scene.triangles.push_back(
        Triangle{{-1.0f, -1.0f, 0.0f}, CR_TRI_REPORT_UV, {1.0f, -1.0f, 0.0f}, 0u, {0.0f, 1.0f, 0.0f}, 0u});
    scene.cones.push_back(Cone{{0.0f, 0.0f, -1.0f}, 1.0f, {0.0f, 0.0f, 1.0f}, 0.5f});
    Finish();
  }
};

const simd::ProbeScene& Probe()
{
  static const MicroScene p;
  return p;
}

const char* kShape[3] = {"Sphere", "Triangle", "Cone"};
const double kMiddleT[3] = {4.0, 5.0, 4.25};

RayRecord MiddleRay(std::uint32_t g)
{
  if (g == 2) return RayRecord{{-5.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY};
  return RayRecord{{0.0f, 0.0f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
}

// Hits of the set in the packet form (N rays a call) and the single form
// (each ray against a pack holding g and padding).
void CountBoth(const KernelProbes& pr, std::uint32_t g, bool fast, const std::vector<RayRecord>& rays, int& packet,
               int& single)
{
  const simd::ProbeScene& ps = Probe();
  std::vector<ProbeResult> out(std::size_t(pr.width)), pout(std::size_t(pr.packWidth));
  packet = single = 0;
  for (std::size_t i = 0; i + std::size_t(pr.width) <= rays.size(); i += std::size_t(pr.width)) {
    pr.packetPrim(ps.sc, &rays[i], g, fast, out.data());
    for (const auto& o : out) packet += o.hit;
  }
  std::vector<std::uint32_t> gs(std::size_t(pr.packWidth), CR_NO_HIT);
  gs[0] = g;
  for (const auto& r : rays) {
    pr.singlePrims(ps.sc, r, gs.data(), fast, pout.data());
    single += pout[0].hit;
  }
}

bool Validate(const KernelProbes& pr, std::uint32_t g, bool fast, const std::vector<RayRecord>& rays,
              benchmark::State& state)
{
  std::vector<RayRecord> mid(std::size_t(pr.width), MiddleRay(g));
  std::vector<ProbeResult> out(std::size_t(pr.width));
  pr.packetPrim(Probe().sc, mid.data(), g, fast, out.data());
  for (const auto& o : out)
    if (!o.hit || std::fabs(double(o.t) - kMiddleT[g]) > 1e-5 * kMiddleT[g]) {
      state.SkipWithError("the middle ray does not hit at the expected distance");
      return false;
    }
  int packet = 0, single = 0;
  CountBoth(pr, g, fast, rays, packet, single);
  if (packet != single || packet == 0 || packet == int(rays.size())) {
    state.SkipWithError("packet and single forms disagree (or the ray set is degenerate)");
    return false;
  }
  return true;
}

void BM_PacketPrim(benchmark::State& state, KernelProbes pr, std::uint32_t g, bool fast)
{
  const auto rays = RaysAtOrigin(kRays, 1.2f, 6.0f, 11);
  if (!Validate(pr, g, fast, rays, state)) return;
  std::vector<ProbeResult> out(std::size_t(pr.width));
  const simd::KernelScene& sc = Probe().sc;
  for (auto _ : state) {
    for (std::size_t i = 0; i + std::size_t(pr.width) <= rays.size(); i += std::size_t(pr.width)) {
      pr.packetPrim(sc, &rays[i], g, fast, out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rays.size()));
}

// K copies of the same primitive in the pack: K tests per call.
void BM_SinglePrims(benchmark::State& state, KernelProbes pr, std::uint32_t g, bool fast)
{
  const auto rays = RaysAtOrigin(kRays, 1.2f, 6.0f, 11);
  if (!Validate(pr, g, fast, rays, state)) return;
  std::vector<std::uint32_t> gs(std::size_t(pr.packWidth), g);
  std::vector<ProbeResult> out(std::size_t(pr.packWidth));
  const simd::KernelScene& sc = Probe().sc;
  for (auto _ : state) {
    for (const auto& r : rays) {
      pr.singlePrims(sc, r, gs.data(), fast, out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rays.size()) * pr.packWidth);
}

void BM_PacketBox(benchmark::State& state, KernelProbes pr, bool fast)
{
  const auto rays = RaysAtOrigin(kRays, 1.6f, 6.0f, 11);
  const float lo[3] = {-1.0f, -1.0f, -1.0f}, hi[3] = {1.0f, 1.0f, 1.0f};
  std::vector<ProbeResult> out(std::size_t(pr.width));
  int hits = 0;
  for (std::size_t i = 0; i + std::size_t(pr.width) <= rays.size(); i += std::size_t(pr.width)) {
    pr.packetBox(lo, hi, &rays[i], fast, out.data());
    for (const auto& o : out) hits += o.hit;
  }
  if (hits == 0 || hits == int(rays.size())) {
    state.SkipWithError("degenerate ray set for the box");
    return;
  }
  for (auto _ : state) {
    for (std::size_t i = 0; i + std::size_t(pr.width) <= rays.size(); i += std::size_t(pr.width)) {
      pr.packetBox(lo, hi, &rays[i], fast, out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rays.size()));
}

// One ray against N boxes (a wide BVH node's children), all the unit cube.
void BM_SingleBoxes(benchmark::State& state, KernelProbes pr, bool fast)
{
  const auto rays = RaysAtOrigin(kRays, 1.6f, 6.0f, 11);
  std::vector<float> lo(3 * std::size_t(pr.width), -1.0f), hi(3 * std::size_t(pr.width), 1.0f);
  std::vector<ProbeResult> out(std::size_t(pr.width));
  for (auto _ : state) {
    for (const auto& r : rays) {
      pr.singleBoxes(lo.data(), hi.data(), r, fast, out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rays.size()) * pr.width);
}

int RegisterAll()
{
#if defined(CELLRAY_SIMD_X86)
  std::vector<std::pair<std::string, KernelProbes>> isas;
  for (const std::string& isa : simd::SupportedVectorIsas())
    isas.emplace_back(isa, simd::IsaProbes(simd::ParseIsa(isa)));
  for (const auto& [isa, pr] : isas) {
    for (bool fast : {false, true}) {
      const char* mode = fast ? "Fast" : "Robust";
      for (std::uint32_t g = 0; g < 3; ++g) {
        benchmark::RegisterBenchmark(fmt::format("BM_Simd/{}/{}_{}/packet{}", isa, kShape[g], mode, pr.width).c_str(),
                                     BM_PacketPrim, pr, g, fast);
        benchmark::RegisterBenchmark(
            fmt::format("BM_Simd/{}/{}_{}/single_pack{}", isa, kShape[g], mode, pr.packWidth).c_str(), BM_SinglePrims,
            pr, g, fast);
      }
      benchmark::RegisterBenchmark(fmt::format("BM_Simd/{}/Box_{}/packet{}", isa, mode, pr.width).c_str(),
                                   BM_PacketBox, pr, fast);
      benchmark::RegisterBenchmark(fmt::format("BM_Simd/{}/Box_{}/single_node{}", isa, mode, pr.width).c_str(),
                                   BM_SingleBoxes, pr, fast);
    }
  }
#endif
  return 0;
}

const int kRegistered = RegisterAll();

}  // namespace

}  // namespace cr::micro
