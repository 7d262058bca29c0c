#include "host/cl/cl_program_cache.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr {

namespace {

constexpr char kMagic[8] = {'C', 'R', 'C', 'L', 'P', 'R', 'O', 'G'};

void PutU32(unsigned char* p, std::uint32_t v)
{
  for (int i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
void PutU64(unsigned char* p, std::uint64_t v)
{
  for (int i = 0; i < 8; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
std::uint32_t GetU32(const unsigned char* p)
{
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= std::uint32_t(p[i]) << (8 * i);
  return v;
}
std::uint64_t GetU64(const unsigned char* p)
{
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t(p[i]) << (8 * i);
  return v;
}

std::uint64_t Mix(std::uint64_t z)
{
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Header layout offsets.
constexpr std::size_t kOffVersion = 8, kOffKeyBytes = 12, kOffHash0 = 16, kOffHash1 = 24, kOffPayloadBytes = 32,
                      kOffPayloadSum = 40, kOffHeaderSum = 48;
static_assert(kOffHeaderSum + 8 <= kClCacheHeaderBytes);

}  // namespace

std::uint64_t ClCacheChecksum(const void* data, std::size_t size, std::uint64_t seed)
{
  const auto* p = static_cast<const unsigned char*>(data);
  std::uint64_t h = 0xCBF29CE484222325ull ^ Mix(seed + size);
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * 0x100000001B3ull;
  }
  for (; i < size; ++i) h = (h ^ p[i]) * 0x100000001B3ull;
  return Mix(h);
}

std::string ClCacheDir()
{
  if (const char* d = std::getenv("CELLRAY_CACHE_DIR"); d && *d) return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/cellray";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/cellray";
  return {};
}

ClCacheKey MakeClCacheKey(const std::string& dir, const std::string& source, const std::string& deviceName,
                          const std::string& driverVersion, const std::string& platformVersion,
                          const std::string& options)
{
  ClCacheKey k;
  k.text = fmt::format(
      "format={}\nsource={:016x}{:016x} {}\ndevice={}\ndriver={}\nplatform={}\noptions={}\n", kClCacheFormatVersion,
      ClCacheChecksum(source.data(), source.size(), 1), ClCacheChecksum(source.data(), source.size(), 2),
      source.size(), deviceName, driverVersion, platformVersion, options);
  if (!dir.empty()) {
    const std::uint64_t h0 = ClCacheChecksum(k.text.data(), k.text.size(), 3);
    const std::uint64_t h1 = ClCacheChecksum(k.text.data(), k.text.size(), 4);
    k.file = (std::filesystem::path(dir) / fmt::format("{:016x}{:016x}.clbin", h0, h1)).string();
  }
  return k;
}

ClCacheLookup LoadClCache(const ClCacheKey& key)
{
  ClCacheLookup r;
  if (key.file.empty()) {
    r.why = "cache off";
    return r;
  }
  std::error_code ec;
  if (!std::filesystem::exists(key.file, ec)) {
    r.why = "absent";
    return r;
  }
  r.corrupt = true;
  std::vector<char> raw;
  try {
    raw = ReadFile(key.file);
  } catch (const std::exception& e) {
    r.why = fmt::format("unreadable ({})", e.what());
    return r;
  }
  const auto* p = reinterpret_cast<const unsigned char*>(raw.data());
  if (raw.size() < kClCacheHeaderBytes) {
    r.why = "truncated header";
    return r;
  }
  if (std::memcmp(p, kMagic, 8) != 0) {
    r.why = "bad magic";
    return r;
  }
  if (GetU32(p + kOffVersion) != kClCacheFormatVersion) {
    r.why = fmt::format("format version {} (expected {})", GetU32(p + kOffVersion), kClCacheFormatVersion);
    return r;
  }
  const std::uint64_t keyBytes = GetU32(p + kOffKeyBytes);
  const std::uint64_t payloadBytes = GetU64(p + kOffPayloadBytes);
  if (keyBytes > raw.size() - kClCacheHeaderBytes) {
    r.why = "truncated key";
    return r;
  }
  const std::size_t headerAll = kClCacheHeaderBytes + static_cast<std::size_t>(keyBytes);
  const std::uint64_t headerSum =
      ClCacheChecksum(p, kOffHeaderSum, ClCacheChecksum(p + kClCacheHeaderBytes, static_cast<std::size_t>(keyBytes)));
  if (headerSum != GetU64(p + kOffHeaderSum)) {
    r.why = "bad header checksum";
    return r;
  }
  if (keyBytes != key.text.size() || std::memcmp(p + kClCacheHeaderBytes, key.text.data(), key.text.size()) != 0) {
    r.why = "stale (key differs)";
    return r;
  }
  if (payloadBytes != raw.size() - headerAll) {
    r.why = fmt::format("truncated payload ({} bytes, header says {})", raw.size() - headerAll, payloadBytes);
    return r;
  }
  if (payloadBytes == 0) {
    r.why = "empty payload";
    return r;
  }
  if (ClCacheChecksum(p + headerAll, static_cast<std::size_t>(payloadBytes)) != GetU64(p + kOffPayloadSum)) {
    r.why = "bad payload checksum";
    return r;
  }
  r.binary.emplace(p + headerAll, p + raw.size());
  r.corrupt = false;
  r.why = "hit";
  return r;
}

bool StoreClCache(const ClCacheKey& key, const std::vector<unsigned char>& binary, std::string* why)
{
  if (key.file.empty()) {
    if (why) *why = "cache off";
    return false;
  }
  try {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(key.file).parent_path(), ec);
    if (ec) throw RuntimeError(fmt::format("cannot create {}: {}", std::filesystem::path(key.file).parent_path().string(),
                                           ec.message()));
    std::vector<unsigned char> out(kClCacheHeaderBytes + key.text.size() + binary.size());
    unsigned char* p = out.data();
    std::memcpy(p, kMagic, 8);
    PutU32(p + kOffVersion, kClCacheFormatVersion);
    PutU32(p + kOffKeyBytes, static_cast<std::uint32_t>(key.text.size()));
    PutU64(p + kOffHash0, ClCacheChecksum(key.text.data(), key.text.size(), 3));
    PutU64(p + kOffHash1, ClCacheChecksum(key.text.data(), key.text.size(), 4));
    PutU64(p + kOffPayloadBytes, binary.size());
    PutU64(p + kOffPayloadSum, ClCacheChecksum(binary.data(), binary.size()));
    std::memcpy(p + kClCacheHeaderBytes, key.text.data(), key.text.size());
    PutU64(p + kOffHeaderSum, ClCacheChecksum(p, kOffHeaderSum, ClCacheChecksum(key.text.data(), key.text.size())));
    std::memcpy(p + kClCacheHeaderBytes + key.text.size(), binary.data(), binary.size());
    WriteFileAtomically(key.file, out.data(), out.size());
    return true;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
}

}  // namespace cr
