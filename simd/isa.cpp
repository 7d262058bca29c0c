#include "simd/isa.h"

#include <fmt/format.h>

#include "host/core/error.h"

namespace cr::simd {

bool IsaSupported(Isa isa)
{
  switch (isa) {
    case Isa::Scalar: return true;
// An ISA counts where the CPU runs it and the build has its kernels
// (CELLRAY_SIMD_ISAS, simd/CMakeLists.txt).
#if defined(CELLRAY_SIMD_SSE4)
    case Isa::Sse4: __builtin_cpu_init(); return __builtin_cpu_supports("sse4.1");
#else
    case Isa::Sse4: return false;
#endif
#if defined(CELLRAY_SIMD_AVX2)
    case Isa::Avx2: __builtin_cpu_init(); return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    case Isa::Avx2: return false;
#endif
#if defined(CELLRAY_SIMD_AVX512)
    case Isa::Avx512:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("avx512f") &&
             __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512bw");
#else
    case Isa::Avx512: return false;
#endif
  }
  return false;
}

Isa BestIsa()
{
  if (IsaSupported(Isa::Avx512)) return Isa::Avx512;
  if (IsaSupported(Isa::Avx2)) return Isa::Avx2;
  if (IsaSupported(Isa::Sse4)) return Isa::Sse4;
  return Isa::Scalar;
}

const char* IsaName(Isa isa)
{
  switch (isa) {
    case Isa::Scalar: return "scalar";
    case Isa::Sse4: return "sse4";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
  }
  return "?";
}

Isa ParseIsa(const std::string& name)
{
  if (name.empty()) return BestIsa();
  Isa isa;
  if (name == "avx512")
    isa = Isa::Avx512;
  else if (name == "avx2")
    isa = Isa::Avx2;
  else if (name == "sse4")
    isa = Isa::Sse4;
  else if (name == "scalar")
    isa = Isa::Scalar;
  else
    throw InputError(fmt::format("unknown --isa '{}' (expected avx512, avx2, sse4 or scalar)", name));
  if (!IsaSupported(isa))
    throw InputError(fmt::format("--isa {}: this CPU (or build) does not support it; best available is {}", name,
                                 IsaName(BestIsa())));
  return isa;
}

std::vector<std::string> SupportedVectorIsas()
{
  std::vector<std::string> out;
  for (Isa isa : {Isa::Sse4, Isa::Avx2, Isa::Avx512})
    if (IsaSupported(isa)) out.push_back(IsaName(isa));
  return out;
}

}  // namespace cr::simd
