// Image output through OpenImageIO: PNG (8-bit, sRGB-encoded) or EXR (float,
// linear), chosen by the extension; written to a temporary name and renamed.
#pragma once

#include <string>
#include <vector>

namespace cr {

// Checks that `path` names an image format we write (.png, .exr; else
// InputError) and that the image module loads (else RuntimeError), so that
// a long render fails before it starts, not when it writes.
void CheckImageOutput(const std::string& path);

// `rgb` holds width * height * 3 linear floats, row-major from the top.
void WriteImage(const std::string& path, int width, int height, const std::vector<float>& rgb);

// OpenImageIO's comparison of two linear images after display encoding
// (sRGB, clamped to [0, 1], as the PNG would hold them).
struct ImageDiff {
  double psnr = 0.0;      // dB; infinite for identical images
  double rmsError = 0.0;
  double meanError = 0.0;
  double maxError = 0.0;
  std::size_t nDiffering = 0;  // pixels differing by more than 1/255
};
ImageDiff CompareImages(int width, int height, const std::vector<float>& a, const std::vector<float>& b);

// Reads an image as linear RGB floats (tests, comparisons).
std::vector<float> ReadImage(const std::string& path, int& width, int& height);

}  // namespace cr
