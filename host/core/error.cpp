#include "host/core/error.h"

#include <atomic>
#include <cstdio>
#include <mutex>

#include <fmt/format.h>

namespace cr {

namespace {
std::atomic<long> gWarnings{0};
std::atomic<bool> gQuiet{false};
std::mutex gWarnMutex;
}  // namespace

InputError::InputError(std::string_view file, long line, std::string_view what)
    : std::runtime_error(line > 0 ? fmt::format("{}:{}: {}", file, line, what) : fmt::format("{}: {}", file, what))
{
}

InputError InputError::Record(std::string_view file, std::uint64_t record, std::string_view what)
{
  return InputError(fmt::format("{}: record {}: {}", file, record, what));
}

void Warn(std::string_view msg)
{
  ++gWarnings;
  if (gQuiet) return;
  std::lock_guard<std::mutex> lock(gWarnMutex);
  std::fprintf(stderr, "cellray: warning: %.*s\n", static_cast<int>(msg.size()), msg.data());
}

long WarningCount() { return gWarnings; }
void SetWarningsQuiet(bool quiet) { gQuiet = quiet; }

}  // namespace cr
