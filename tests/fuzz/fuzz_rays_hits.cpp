// libFuzzer target: the .rays and .hits readers (io/rays_io.cpp, format in
// ../shared/FORMATS.md). The input is written to a file and read as both a
// ray set and a hit set (each rejects the other's magic at once). A set that
// reads must write back byte for byte: the formats have one encoding (a
// ray set with times, CRRAYS02, is read and written with them; an empty
// CRRAYS02 set has no times and is written as an empty CRRAYS01 set).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

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
    std::vector<float> times;
    std::vector<cr::RayRecord> rays = cr::ReadRays(path, &times);
    cr::WriteRays(out, rays, times);  // RuntimeError if the reader let an invalid ray or time through
    if (rays.empty() && size >= 8 && std::memcmp(data, cr::kRaysTimedMagic, 8) == 0) {
      std::vector<std::uint8_t> plain(data, data + size);
      std::memcpy(plain.data(), cr::kRaysMagic, 8);
      CheckRoundTrip(out, plain.data(), plain.size());
    } else {
      CheckRoundTrip(out, data, size);
    }
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
