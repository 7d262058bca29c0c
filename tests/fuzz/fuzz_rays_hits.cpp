// libFuzzer target: the .rays and .hits readers (io/rays_io.cpp, format in
// ../shared/FORMATS.md). The input is written to a file and read as both a
// ray set and a hit set (each rejects the other's magic at once). A set that
// reads must write back byte for byte: the formats have one encoding.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "host/core/file_util.h"
#include "tests/fuzz/fuzz_util.h"
#include "host/io/rays_io.h"

namespace {

void CheckRoundTrip(const std::string& written, const std::uint8_t* data, std::size_t size)
{
  std::vector<char> back = cr::ReadFile(written);
  if (back.size() != size || (size && std::memcmp(back.data(), data, size) != 0))
    cr::fuzz::Fail("a set that reads does not write back identically:", written);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string path =
      cr::fuzz::WriteTemp("in.bin", std::string_view(reinterpret_cast<const char*>(data), size));
  const std::string out = cr::fuzz::TempDir() + "/out.bin";
  try {
    std::vector<cr::RayRecord> rays = cr::ReadRays(path);
    cr::WriteRays(out, rays);  // RuntimeError if the reader let an invalid ray through
    CheckRoundTrip(out, data, size);
  } catch (const cr::InputError& e) {
    cr::fuzz::CheckMessage(e, path);
  }
  try {
    std::vector<cr::HitRecord> hits = cr::ReadHits(path);
    cr::WriteHits(out, hits);
    CheckRoundTrip(out, data, size);
  } catch (const cr::InputError& e) {
    cr::fuzz::CheckMessage(e, path);
  }
  return 0;
}
