// libFuzzer target: the NFF reader (scene/nff.cpp, with the polygon
// triangulation it calls), on the input as an in-memory scene file. Accepts
// what LoadNFF accepts: a scene with at least one geometry statement.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
  cr::SetWarningsQuiet(true);  // degenerate primitives warn; millions of lines would drown the report
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const std::string kName = "fuzz.nff";
  cr::Scene scene;
  try {
    cr::ParseNFF(std::string_view(reinterpret_cast<const char*>(data), size), kName, scene, false);
  } catch (const cr::InputError& e) {
    cr::fuzz::CheckMessage(e, kName);
    return 0;
  }
  cr::fuzz::CheckScene(scene);
  return 0;
}
