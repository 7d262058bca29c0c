// Output files are never half-written: data goes to a temporary name beside
// the target and is renamed over it only when complete.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace cr {

// Calls write(tmpPath), then renames tmpPath to path. On any exception the
// temporary is removed and the exception propagates; the target is untouched.
void WriteAtomically(const std::string& path, const std::function<void(const std::string& tmpPath)>& write);

// Writes bytes to path atomically (RuntimeError on failure).
void WriteFileAtomically(const std::string& path, const void* data, std::size_t size);

// Reads a whole file; InputError "FILE: cannot open" when missing.
std::vector<char> ReadFile(const std::string& path);

// Size of a regular file, or InputError if it does not exist / is not a file.
std::size_t FileSize(const std::string& path);

}  // namespace cr
