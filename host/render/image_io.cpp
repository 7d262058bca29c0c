// Image I/O through the image module (host/render/image_module.h), opened
// on the first call: the core does not link OpenImageIO.
#include "host/render/image_io.h"

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/render/image_module.h"

namespace cr {
namespace {

namespace fs = std::filesystem;

// Where the module may be: $CELLRAY_IMAGE_MODULE (a file), then beside the
// executable (the CLI, tests and benchmarks: <build>/bin), then beside the
// object that holds this code (the Python extension, in its package).
std::vector<std::string> ModuleCandidates()
{
  std::vector<std::string> out;
  if (const char* env = std::getenv("CELLRAY_IMAGE_MODULE"); env && *env) {
    out.emplace_back(env);
    return out;
  }
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) out.push_back((exe.parent_path() / kImageModuleFile).string());
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&ModuleCandidates), &info) && info.dli_fname &&
      std::string_view(info.dli_fname).find('/') != std::string_view::npos) {
    std::string here = (fs::absolute(fs::path(info.dli_fname), ec).parent_path() / kImageModuleFile).string();
    if (std::find(out.begin(), out.end(), here) == out.end()) out.push_back(here);
  }
  return out;
}

const ImageModule& Module()
{
  static const ImageModule* module = nullptr;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : ModuleCandidates()) {
      if (!fs::exists(path)) {
        tried += fmt::format("{}{} (absent)", tried.empty() ? "" : ", ", path);
        continue;
      }
      // RTLD_NOW: a module with a missing library fails here, with its name.
      void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        tried += fmt::format("{}{} ({})", tried.empty() ? "" : ", ", path, dlerror());
        continue;
      }
      auto entry = reinterpret_cast<const ImageModule* (*)()>(dlsym(handle, kImageModuleEntry));
      const ImageModule* m = entry ? entry() : nullptr;
      if (!m || m->version != kImageModuleVersion) {
        tried += fmt::format("{}{} (not version {} of cellray's image module: rebuild it)",
                             tried.empty() ? "" : ", ", path, kImageModuleVersion);
        dlclose(handle);
        continue;
      }
      module = m;  // kept open for the life of the process
      return;
    }
    failure = fmt::format("image support ({}, OpenImageIO) cannot be loaded: tried {}; set CELLRAY_IMAGE_MODULE "
                          "to its path",
                          kImageModuleFile, tried.empty() ? "nothing" : tried);
  });
  if (!module) throw RuntimeError(failure);
  return *module;
}

std::string LowerExtension(const std::string& path)
{
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace

namespace {
// "png" or "exr", by the extension of an output path; InputError otherwise.
std::string OutputFormat(const std::string& path)
{
  const std::string ext = LowerExtension(path);
  if (ext != ".exr" && ext != ".png") throw InputError(fmt::format("{}: unsupported image format (use .png or .exr)", path));
  return ext.substr(1);
}
}  // namespace

void CheckImageOutput(const std::string& path)
{
  OutputFormat(path);
  Module();
}

void WriteImage(const std::string& path, int width, int height, const std::vector<float>& rgb)
{
  const std::string format = OutputFormat(path);
  if (rgb.size() != std::size_t(width) * height * 3) throw RuntimeError(fmt::format("{}: image size mismatch", path));
  const ImageModule& m = Module();
  WriteAtomically(path, [&](const std::string& tmp) {
    // The temporary name keeps the extension: OpenImageIO picks the format by it.
    if (std::string err = m.write(tmp, format, width, height, rgb); !err.empty())
      throw RuntimeError(fmt::format("{}: {}", path, err));
  });
}

ImageDiff CompareImages(int width, int height, const std::vector<float>& a, const std::vector<float>& b)
{
  if (a.size() != std::size_t(width) * height * 3 || b.size() != a.size())
    throw RuntimeError("CompareImages: image sizes differ");
  ImageDiff d;
  if (std::string err = Module().compare(width, height, a, b, d); !err.empty()) throw RuntimeError(err);
  return d;
}

std::vector<float> ReadImage(const std::string& path, int& width, int& height)
{
  std::vector<float> rgb;
  if (std::string err = Module().read(path, LowerExtension(path) == ".exr", width, height, rgb); !err.empty())
    throw InputError(fmt::format("{}: {}", path, err));
  return rgb;
}

}  // namespace cr
