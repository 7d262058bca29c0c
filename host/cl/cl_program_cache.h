// On-disk cache of compiled OpenCL programs (CL_PROGRAM_BINARIES), so that a
// second run skips the compiler.
//
// Directory: $CELLRAY_CACHE_DIR, else $XDG_CACHE_HOME/cellray, else
// ~/.cache/cellray. An entry is keyed by the kernel source, the device name,
// the driver and platform versions and the build options. Each file is
//   header (64 bytes, little-endian):
//     magic "CRCLPROG", u32 format version, u32 key text bytes,
//     u64 key hash[2], u64 payload bytes, u64 payload checksum,
//     u64 header checksum (over the 56 bytes before it and the key text)
//   key text (the full key, compared on load, so a hash collision is harmless)
//   payload (the device's program binary)
// and is checked completely before use (tinybvh's Load): a missing, stale,
// truncated or corrupt entry is never trusted; the caller rebuilds from source
// and Store() replaces it, writing to a temporary name and renaming.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cr {

struct ClCacheKey {
  std::string text;    // every input of the key, one "name=value" per line
  std::string file;    // <dir>/<hash>.clbin, empty when caching is off
};

// The cache directory (empty when neither variable nor $HOME is set).
std::string ClCacheDir();

ClCacheKey MakeClCacheKey(const std::string& dir, const std::string& source, const std::string& deviceName,
                          const std::string& driverVersion, const std::string& platformVersion,
                          const std::string& options);

// Outcome of a lookup: the binary, or why there is none ("absent", or what
// was wrong with the entry: "truncated", "bad checksum", ...).
struct ClCacheLookup {
  std::optional<std::vector<unsigned char>> binary;
  std::string why;
  bool corrupt = false;  // an entry existed but could not be trusted
};
ClCacheLookup LoadClCache(const ClCacheKey& key);

// Writes the entry atomically; returns false (and says why) when the cache
// directory is not writable. Never throws: a cache is an optimisation.
bool StoreClCache(const ClCacheKey& key, const std::vector<unsigned char>& binary, std::string* why = nullptr);

// 64-bit checksum of a byte range (word-wise FNV-1a; every single-word change
// alters it). Exposed for tests.
std::uint64_t ClCacheChecksum(const void* data, std::size_t size, std::uint64_t seed = 0);

inline constexpr std::uint32_t kClCacheFormatVersion = 1;
inline constexpr std::size_t kClCacheHeaderBytes = 64;

}  // namespace cr
