// Instruction sets of the SIMD backend, detected at run time (CPUID through
// __builtin_cpu_supports): nothing in the program assumes AVX2 at compile
// time; only the kernel units of one ISA are compiled with its flags.
#pragma once

#include <string>
#include <vector>

namespace cr::simd {

enum class Isa { Scalar, Sse4, Avx2, Avx512 };

// The best ISA this CPU runs: avx512 (F, VL, DQ, BW; the AVX2 kernels with
// 32 registers and mask compares), else avx2 (with FMA), else sse4 (SSE4.1),
// else scalar.
Isa BestIsa();
bool IsaSupported(Isa isa);
const char* IsaName(Isa isa);
// "avx512", "avx2", "sse4", "scalar", or empty for BestIsa(). InputError for an unknown
// name or an ISA this CPU (or this build) lacks.
Isa ParseIsa(const std::string& name);
// The vector ISAs this CPU runs (and this build has), by name, narrowest
// first ("sse4", "avx2", "avx512").
std::vector<std::string> SupportedVectorIsas();

}  // namespace cr::simd
