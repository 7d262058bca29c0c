// libFuzzer target: the OBJ reader with its NFF-style view file
// (scene/obj.cpp, tinyobjloader, scene/nff.cpp in view-only mode). The input
// is the OBJ text, optionally followed by the separator "%%VIEW%%" and the
// text of NAME.view; both are written to a private temporary directory
// (no separator: no view file) and read with LoadOBJ, as `cellray` would.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
  cr::SetWarningsQuiet(true);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static constexpr std::string_view kSeparator = "%%VIEW%%";
  std::string_view in(reinterpret_cast<const char*>(data), size);
  std::string_view obj = in, view;
  const std::size_t at = in.find(kSeparator);
  if (at != std::string_view::npos) {
    obj = in.substr(0, at);
    view = in.substr(at + kSeparator.size());
  }
  const std::string objPath = cr::fuzz::WriteTemp("f.obj", obj);
  const std::string viewPath = cr::fuzz::TempDir() + "/f.view";
  if (at != std::string_view::npos) {
    cr::fuzz::WriteTemp("f.view", view);
  } else {
    std::error_code ec;
    std::filesystem::remove(viewPath, ec);
  }
  try {
    cr::Scene scene = cr::LoadOBJ(objPath);
    cr::fuzz::CheckScene(scene);
  } catch (const cr::InputError& e) {
    cr::fuzz::CheckMessage(e, objPath, viewPath);
  }
  return 0;
}
