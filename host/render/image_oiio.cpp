// The image module (host/render/image_module.h): image I/O and comparison
// through OpenImageIO, built as libcellray_image.so and opened on first use.
#include <exception>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "host/render/image_module.h"

namespace cr {
namespace {

OIIO::ImageBuf Wrap(int width, int height, const std::vector<float>& rgb)
{
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
  return OIIO::ImageBuf(spec, const_cast<float*>(rgb.data()));
}

std::string Write(const std::string& path, const std::string& format, int width, int height,
                  const std::vector<float>& rgb)
try {
  const bool exr = format == "exr";
  OIIO::ImageBuf linear = Wrap(width, height, rgb);
  OIIO::ImageBuf out;
  if (exr) {
    out = linear;
  } else {
    out = OIIO::ImageBufAlgo::colorconvert(linear, "linear", "sRGB");
    if (out.has_error()) return "colour conversion failed: " + out.geterror();
  }
  // No time stamp: OpenImageIO writes the time of writing into an EXR
  // (DateTime, OpenEXR's capDate) unless the attribute is set, empty
  // suppresses it, so that the same render gives the same file.
  out.specmod().attribute("DateTime", "");
  if (!out.write(path, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8))
    return "cannot write image: " + out.geterror();
  return {};
} catch (const std::exception& e) {
  return std::string("cannot write image: ") + e.what();
}

// Display encoding: sRGB, clamped to [0, 1], as the PNG would hold them.
OIIO::ImageBuf Display(int width, int height, const std::vector<float>& rgb)
{
  OIIO::ImageBuf srgb = OIIO::ImageBufAlgo::colorconvert(Wrap(width, height, rgb), "linear", "sRGB");
  return OIIO::ImageBufAlgo::clamp(srgb, 0.0f, 1.0f);
}

std::string Compare(int width, int height, const std::vector<float>& a, const std::vector<float>& b,
                    ImageDiff& d)
try {
  OIIO::ImageBuf A = Display(width, height, a), B = Display(width, height, b);
  auto r = OIIO::ImageBufAlgo::compare(A, B, 1.0f / 255.0f, 1.0f / 255.0f);
  d.psnr = r.PSNR;
  d.rmsError = r.rms_error;
  d.meanError = r.meanerror;
  d.maxError = r.maxerror;
  d.nDiffering = std::size_t(r.nfail);
  return {};
} catch (const std::exception& e) {
  return std::string("image comparison failed: ") + e.what();
}

std::string Read(const std::string& path, bool linear, int& width, int& height, std::vector<float>& rgb)
try {
  OIIO::ImageBuf in(path);
  if (!in.read(0, 0, true, OIIO::TypeDesc::FLOAT)) return "cannot read image: " + in.geterror();
  OIIO::ImageBuf lin = linear ? in : OIIO::ImageBufAlgo::colorconvert(in, "sRGB", "linear");
  if (lin.has_error()) return "colour conversion failed: " + lin.geterror();
  const OIIO::ImageSpec& spec = lin.spec();
  width = spec.width;
  height = spec.height;
  rgb.assign(std::size_t(width) * height * 3, 0.0f);
  lin.get_pixels(OIIO::ROI(0, width, 0, height, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, rgb.data());
  return {};
} catch (const std::exception& e) {
  return std::string("cannot read image: ") + e.what();
}

constexpr ImageModule kModule{kImageModuleVersion, &Write, &Compare, &Read};

}  // namespace
}  // namespace cr

extern "C" __attribute__((visibility("default"))) const cr::ImageModule* cellray_image_module()
{
  return &cr::kModule;
}
