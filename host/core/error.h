// Errors at the boundaries. Every diagnostic about input carries its location
// (file and line, or record index for binary files) and is caught once, in
// main(), which prints `cellray: <message>` and exits 2 for bad input, 1 for
// runtime failures (OpenCL, memory, I/O on output).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace cr {

inline constexpr int kExitBadInput = 2;
inline constexpr int kExitRuntime = 1;

// Bad input: a scene, view, ray or hit file, or a command-line value.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
  // "FILE:LINE: what" (line 0 means the file as a whole: "FILE: what").
  InputError(std::string_view file, long line, std::string_view what);
  // "FILE: record N: what", for binary formats.
  static InputError Record(std::string_view file, std::uint64_t record, std::string_view what);
};

// A failure that is not the input's fault: OpenCL, allocation, writing output.
class RuntimeError : public std::runtime_error {
 public:
  explicit RuntimeError(const std::string& what) : std::runtime_error(what) {}
};

// Prints "cellray: warning: <msg>" on stderr (never stdout: stdout is JSON).
void Warn(std::string_view msg);
// Number of warnings printed so far (tests use it).
long WarningCount();
// Silences warnings (for tests that provoke many on purpose).
void SetWarningsQuiet(bool quiet);

}  // namespace cr
