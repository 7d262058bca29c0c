// Image output through OpenImageIO: PNG (8-bit, sRGB-encoded) or EXR (float,
// linear), chosen by the extension; written to a temporary name and renamed.
#pragma once

#include <string>
#include <vector>

namespace cr {

// `rgb` holds width * height * 3 linear floats, row-major from the top.
void WriteImage(const std::string& path, int width, int height, const std::vector<float>& rgb);

// Reads an image as linear RGB floats (tests, comparisons).
std::vector<float> ReadImage(const std::string& path, int& width, int& height);

}  // namespace cr
