// The machine and build a bench run measured, for results.json: CPU model,
// cores, frequency governor (when readable), load average, git commit of the
// source tree, date, compiler, SIMD ISA, Embree version.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

namespace cr::bench {

nlohmann::json MachineInfo(const std::string& sourceRoot);

// The 1-minute load average (/proc/loadavg), or -1 when unreadable: timings
// taken while it exceeds the core count are noise (docs/BENCHMARKS.md).
double LoadAverage1();

// Peak resident set of this process (VmHWM), and its reset (Linux
// /proc/self/clear_refs "5", after returning freed heap to the system), so
// that a study can attribute a peak to one configuration; the peak still
// includes what is alive across configurations (the scene, the reference,
// the ray sets). 0 / false where unsupported.
std::uint64_t PeakRssBytes();
std::uint64_t CurrentRssBytes();  // VmRSS (0: unknown)
bool ResetPeakRss();

// UTC date and time, ISO 8601.
std::string UtcNow();

}  // namespace cr::bench
