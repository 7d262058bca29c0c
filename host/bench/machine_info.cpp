#include "host/bench/machine_info.h"

#include <malloc.h>

#include <array>
#include <cstdio>
#include <ctime>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include "host/core/version.h"
#include "simd/isa.h"
#include "host/trace/tracer.h"

#ifdef CELLRAY_HAVE_EMBREE
#include <embree3/rtcore_config.h>
#endif

namespace cr::bench {

namespace {

std::string FirstLine(const std::string& path)
{
  std::ifstream f(path);
  std::string line;
  if (!f || !std::getline(f, line)) return "";
  return line;
}

std::string CpuModel()
{
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      auto c = line.find(':');
      if (c != std::string::npos) return line.substr(line.find_first_not_of(" \t", c + 1));
    }
  return "unknown";
}

// Output of a git command in the source tree, or "" (no git, not a checkout).
std::string Git(const std::string& root, const std::string& args)
{
  if (root.empty()) return "";
  const std::string cmd = fmt::format("git -C '{}' {} 2>/dev/null", root, args);
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) return "";
  std::array<char, 256> buf{};
  std::string out;
  while (std::fgets(buf.data(), int(buf.size()), p)) out += buf.data();
  pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

}  // namespace

double LoadAverage1()
{
  std::ifstream f("/proc/loadavg");
  double a = -1.0;
  if (!(f >> a)) return -1.0;
  return a;
}

namespace {
std::uint64_t StatusKb(const char* key)  // "VmHWM:   1234 kB" -> bytes
{
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(key);
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0) return std::stoull(line.substr(n)) * 1024;
  return 0;
}
}  // namespace

std::uint64_t PeakRssBytes() { return StatusKb("VmHWM:"); }
std::uint64_t CurrentRssBytes() { return StatusKb("VmRSS:"); }

bool ResetPeakRss()
{
  // Freed heap that glibc keeps would count towards the next peak: give it
  // back first, so a peak belongs to what was allocated after the reset.
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  return bool(f);
}

std::string UtcNow()
{
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

nlohmann::json MachineInfo(const std::string& sourceRoot)
{
  nlohmann::json j;
  j["cpu_model"] = CpuModel();
  j["hardware_threads"] = std::thread::hardware_concurrency();
  j["tbb_concurrency"] = tbb::info::default_concurrency();
  const std::string gov = FirstLine("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor");
  j["governor"] = gov.empty() ? "unreadable (no cpufreq in this machine or container)" : gov;
  j["load_average_1min"] = LoadAverage1();
  std::string commit = Git(sourceRoot, "rev-parse HEAD");
  if (!commit.empty() && !Git(sourceRoot, "status --porcelain --untracked-files=no").empty()) commit += "-dirty";
  j["git_commit"] = commit.empty() ? "unknown" : commit;
  j["build_commit"] = BuildCommit();  // the binary's, which may differ from the tree's
  j["date"] = UtcNow();
  j["compiler"] = __VERSION__;
#ifdef NDEBUG
  j["build_type"] = "release";
#else
  j["build_type"] = "debug";
#endif
  j["simd_isa"] = simd::IsaName(simd::BestIsa());
#ifdef CELLRAY_HAVE_EMBREE
  j["embree"] = RTC_VERSION_STRING;
#else
  j["embree"] = nullptr;
#endif
  return j;
}

}  // namespace cr::bench
