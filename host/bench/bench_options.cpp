#include "host/bench/bench_options.h"

#include <algorithm>

#include <fmt/format.h>

namespace cr::bench {

std::string Combo::Label() const
{
  std::string s = BackendName(backend);
  if (backend != Backend::Embree) s += fmt::format(" {}", AccelKindName(accel));
  if (!variant.empty()) {
    std::string v = variant;
    if (auto p = v.find("-robust"); p != std::string::npos) v.replace(p, 7, " robust");
    s += " " + v;
  }
  if (backend != Backend::Embree && precision != Precision::Robust) s += fmt::format(" {}", PrecisionName(precision));
  return s;
}

namespace {

bool Has(const std::vector<Precision>& v, Precision p) { return std::find(v.begin(), v.end(), p) != v.end(); }

// Whether a backend has a precision mode (SIMD: robust and fast, its fp64 is
// the scalar kernels; Embree: its own arithmetic, listed once).
bool HasMode(Backend b, Precision p, bool openclHasFp64)
{
  switch (b) {
    case Backend::Reference: return true;
    case Backend::Scalar: return true;
    case Backend::Simd: return p != Precision::Fp64;
    case Backend::OpenCL: return p != Precision::Fp64 || openclHasFp64;
    case Backend::Embree: return p == Precision::Robust;
  }
  return false;
}

// The SIMD BVH's two walks by name, beside `auto`'s choice (robust rows
// only): Embree's rows are its single and packet8 walks, so "our fastest
// against Embree's fastest" takes the same choice on both sides (`auto`'s
// pilot misses the faster walk on some sets, docs/SIMD.md).
template <class Add>
void AddSimdBvhWalks(Add& add, Precision p)
{
  if (p != Precision::Robust) return;
  add(Backend::Simd, AccelKind::BVH, p, "single");
  add(Backend::Simd, AccelKind::BVH, p, "packet");
}

}  // namespace

std::vector<Combo> PlanCombos(const BenchOptions& o, bool openclHasFp64, bool openclAvailable)
{
  const bool defaults = o.backends.empty() && o.accels.empty() && o.precisions.empty();
  std::vector<Combo> out;
  auto add = [&](Backend b, AccelKind a, Precision p, std::string v = "") {
    if (b == Backend::OpenCL && !openclAvailable) return;
    if (b == Backend::Embree && !EmbreeAvailable()) return;
    out.push_back(Combo{b, a, p, std::move(v)});
  };
  const std::vector<AccelKind> allAccels(std::begin(kAccelKinds), std::end(kAccelKinds));
  if (defaults) {
    // Speed: every structure on the CPU default and on OpenCL, the packet,
    // stackless, wide and wide-packet variants, Embree.
    for (AccelKind a : allAccels) add(Backend::Simd, a, Precision::Robust);
    AddSimdBvhWalks(add, Precision::Robust);
    // The OpenCL BVH's stack walk is named: without a name a CPU device
    // walks it wide (ClResolveDefaultVariant), a row of its own below.
    for (AccelKind a : allAccels) add(Backend::OpenCL, a, Precision::Robust, a == AccelKind::BVH ? "ray" : "");
    add(Backend::OpenCL, AccelKind::BVH, Precision::Robust, "packet");
    add(Backend::OpenCL, AccelKind::BVH, Precision::Robust, "stackless");
    add(Backend::OpenCL, AccelKind::BVH, Precision::Robust, "wide");
    add(Backend::OpenCL, AccelKind::BVH, Precision::Robust, "wide-packet");
    add(Backend::Embree, AccelKind::BVH, Precision::Robust, "single");
    add(Backend::Embree, AccelKind::BVH, Precision::Robust, "packet8");
    add(Backend::Embree, AccelKind::BVH, Precision::Robust, "single-robust");
    // Speed against error: the precision modes on the BVH.
    add(Backend::Scalar, AccelKind::BVH, Precision::Robust);
    add(Backend::Scalar, AccelKind::BVH, Precision::Fast);
    add(Backend::Scalar, AccelKind::BVH, Precision::Fp64);
    add(Backend::Simd, AccelKind::BVH, Precision::Fast);
    add(Backend::OpenCL, AccelKind::BVH, Precision::Fast);
    if (openclHasFp64) add(Backend::OpenCL, AccelKind::BVH, Precision::Fp64);
    return out;
  }
  const std::vector<Backend> backends =
      o.backends.empty() ? std::vector<Backend>{Backend::Simd, Backend::OpenCL, Backend::Embree} : o.backends;
  const std::vector<AccelKind> accels = o.accels.empty() ? allAccels : o.accels;
  const std::vector<Precision> precs = o.precisions.empty() ? std::vector<Precision>{Precision::Robust} : o.precisions;
  for (Backend b : backends) {
    if (b == Backend::Embree) {
      // Embree builds its own BVH and has one arithmetic: listed once per
      // variant, whatever the structure and precision lists say.
      add(b, AccelKind::BVH, Precision::Robust, "single");
      add(b, AccelKind::BVH, Precision::Robust, "packet8");
      if (Has(precs, Precision::Robust) || precs.size() > 1) add(b, AccelKind::BVH, Precision::Robust, "single-robust");
      continue;
    }
    if (b == Backend::Reference) {
      add(b, AccelKind::BVH, Precision::Fp64);  // its own fp64 BVH, whatever the lists say
      continue;
    }
    for (AccelKind a : accels)
      for (Precision p : precs) {
        if (!HasMode(b, p, openclHasFp64)) continue;
        add(b, a, p, b == Backend::OpenCL && a == AccelKind::BVH ? "ray" : "");
        if (b == Backend::Simd && a == AccelKind::BVH) AddSimdBvhWalks(add, p);
        if (b == Backend::OpenCL && a == AccelKind::BVH) {
          add(b, a, p, "packet");
          add(b, a, p, "stackless");
          add(b, a, p, "wide");
          if (p != Precision::Fp64) add(b, a, p, "wide-packet");
        }
      }
  }
  return out;
}

}  // namespace cr::bench
