#include "host/render/image_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr {

void WriteImage(const std::string& path, int width, int height, const std::vector<float>& rgb)
{
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  const bool exr = ext == ".exr";
  if (!exr && ext != ".png") throw InputError(fmt::format("{}: unsupported image format (use .png or .exr)", path));
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
  OIIO::ImageBuf linear(spec, const_cast<float*>(rgb.data()));
  OIIO::ImageBuf out;
  if (exr) {
    out = linear;
  } else {
    out = OIIO::ImageBufAlgo::colorconvert(linear, "linear", "sRGB");
    if (out.has_error()) throw RuntimeError(fmt::format("{}: colour conversion failed: {}", path, out.geterror()));
  }
  // No time stamp: OpenImageIO writes the time of writing into an EXR
  // (DateTime, OpenEXR's capDate) unless the attribute is set, empty
  // suppresses it, so that the same render gives the same file.
  out.specmod().attribute("DateTime", "");
  WriteAtomically(path, [&](const std::string& tmp) {
    if (!out.write(tmp, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8))
      throw RuntimeError(fmt::format("{}: cannot write image: {}", path, out.geterror()));
  });
}

namespace {
OIIO::ImageBuf Display(int width, int height, const std::vector<float>& rgb)
{
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
  OIIO::ImageBuf lin(spec, const_cast<float*>(rgb.data()));
  OIIO::ImageBuf srgb = OIIO::ImageBufAlgo::colorconvert(lin, "linear", "sRGB");
  return OIIO::ImageBufAlgo::clamp(srgb, 0.0f, 1.0f);
}
}  // namespace

ImageDiff CompareImages(int width, int height, const std::vector<float>& a, const std::vector<float>& b)
{
  if (a.size() != std::size_t(width) * height * 3 || b.size() != a.size())
    throw RuntimeError("CompareImages: image sizes differ");
  OIIO::ImageBuf A = Display(width, height, a), B = Display(width, height, b);
  auto r = OIIO::ImageBufAlgo::compare(A, B, 1.0f / 255.0f, 1.0f / 255.0f);
  ImageDiff d;
  d.psnr = r.PSNR;
  d.rmsError = r.rms_error;
  d.meanError = r.meanerror;
  d.maxError = r.maxerror;
  d.nDiffering = std::size_t(r.nfail);
  return d;
}

std::vector<float> ReadImage(const std::string& path, int& width, int& height)
{
  OIIO::ImageBuf in(path);
  if (!in.read(0, 0, true, OIIO::TypeDesc::FLOAT))
    throw InputError(fmt::format("{}: cannot read image: {}", path, in.geterror()));
  OIIO::ImageBuf lin = in;
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".exr" && ext != ".EXR") lin = OIIO::ImageBufAlgo::colorconvert(in, "sRGB", "linear");
  const OIIO::ImageSpec& spec = lin.spec();
  width = spec.width;
  height = spec.height;
  std::vector<float> rgb(std::size_t(width) * height * 3);
  lin.get_pixels(OIIO::ROI(0, width, 0, height, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, rgb.data());
  return rgb;
}

}  // namespace cr
