// --device all (or a list, --device 0,1): every OpenCL device traces, sharing each
// batch (docs/DISTRIBUTED.md, "Several devices in one process"). Each device
// has its own tracer (its own context, program and copy of the structure);
// a batch is cut into slices that the devices take from a shared counter as
// they finish the last, so a fast GPU takes more slices than a slow CPU
// device. A ray's answer does not depend on the slice it falls in.
#include <algorithm>
#include <atomic>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "host/cl/cl_device.h"
#include "host/core/error.h"
#include "host/trace/tracer.h"

namespace cr {

std::unique_ptr<Tracer> CreateOpenCLTracer(const Scene& scene, const TraceConfig& config);

namespace {

class MultiDeviceTracer final : public Tracer {
 public:
  MultiDeviceTracer(const Scene& scene, const TraceConfig& config)
  {
    std::vector<ClDevice> use;
    if (config.device == "all") {
      std::vector<ClDevice> all = ListClDevices();
      for (const ClDevice& d : all)
        if (d.available && !d.simulator) use.push_back(d);
      if (use.empty())  // only a simulator (Oclgrind's wrapper): use what there is
        for (const ClDevice& d : all)
          if (d.available) use.push_back(d);
      if (use.empty()) throw RuntimeError("--device all: no available OpenCL device");
    } else {
      // A list "0,2" (a device may be named twice: two contexts on it).
      std::size_t at = 0;
      while (at <= config.device.size()) {
        const std::size_t comma = std::min(config.device.find(',', at), config.device.size());
        const std::string one = config.device.substr(at, comma - at);
        if (one.empty()) throw InputError(fmt::format("--device '{}': an empty name in the list", config.device));
        use.push_back(SelectClDevice(one));
        at = comma + 1;
      }
    }
    for (const ClDevice& d : use) {
      TraceConfig c = config;
      c.device = std::to_string(d.flatIndex);
      members_.push_back(CreateOpenCLTracer(scene, c));
      sliced_.push_back(0);
    }
    info_ = members_[0]->Info();
    for (std::size_t i = 1; i < members_.size(); ++i) info_.buildMs += members_[i]->Info().buildMs;
  }

  using Tracer::Trace;
  void TraceRays(RaySpan rays, TimeSpan times, std::vector<HitRecord>& hits,
             bool occlusion, TraceStatsSum* stats) override
  {
    const std::size_t n = rays.size(), d = members_.size();
    hits.resize(n);
    if (d == 1) {
      TraceInRange(*members_[0], rays, times, hits, occlusion, stats);
      ++sliced_[0];
      return;
    }
    // Slices of at least 8192 rays (a device's launch needs a batch), about
    // four per device per batch.
    const std::size_t slice = std::max<std::size_t>(8192, (n + 4 * d - 1) / (4 * d));
    const std::size_t nSlices = (n + slice - 1) / slice;
    std::atomic<std::size_t> next{0};
    std::vector<TraceStatsSum> part(d);
    tbb::parallel_for(std::size_t(0), d, std::size_t(1), [&](std::size_t k) {
      std::vector<RayRecord> r;
      std::vector<float> t;
      std::vector<HitRecord> h;
      for (std::size_t s = next++; s < nSlices; s = next++) {
        const std::size_t b = s * slice, e = std::min(n, b + slice);
        r.assign(rays.begin() + std::ptrdiff_t(b), rays.begin() + std::ptrdiff_t(e));
        if (!times.empty()) t.assign(times.begin() + std::ptrdiff_t(b), times.begin() + std::ptrdiff_t(e));
        TraceInRange(*members_[k], r, t, h, occlusion, stats ? &part[k] : nullptr);
        std::copy(h.begin(), h.end(), hits.begin() + std::ptrdiff_t(b));
        ++sliced_[k];
      }
    });
    if (stats)
      for (const TraceStatsSum& p : part) AddStats(*stats, p);
  }
  void Prepare(bool occlusion, bool primary) override
  {
    for (auto& m : members_) m->Prepare(occlusion, false);
    (void)primary;  // primary rays are traced as a batch from the host (Tracer::TracePrimary)
  }
  void Describe(nlohmann::json& j) const override
  {
    nlohmann::json devices = nlohmann::json::array();
    for (std::size_t k = 0; k < members_.size(); ++k)
      devices.push_back({{"device", members_[k]->DeviceName()}, {"slices", sliced_[k]}});
    j["devices"] = devices;
  }
  std::string DeviceName() const override
  {
    std::string s;
    for (const auto& m : members_) s += (s.empty() ? "" : " + ") + m->DeviceName();
    return s;
  }
  std::string VariantName() const override { return members_[0]->VariantName(); }

 private:
  std::vector<std::unique_ptr<Tracer>> members_;
  std::vector<std::uint64_t> sliced_;  // slices each device traced
};

}  // namespace

std::unique_ptr<Tracer> CreateMultiDeviceTracer(const Scene& scene, const TraceConfig& config)
{
  return std::make_unique<MultiDeviceTracer>(scene, config);
}

}  // namespace cr
