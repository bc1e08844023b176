// PNG through libpng (the most common output, without loading OpenImageIO).
#pragma once

#include <kdrt/image.h>

#include <string>
#include <vector>

namespace kdrt::detail {

// 8-bit RGB, rows top to bottom. `srgb` adds the sRGB chunk (the samples are
// sRGB-encoded); without it no colour chunk is written, as before.
std::vector<unsigned char> encode_png(const unsigned char* rgb, int width, int height, bool srgb);

// Any PNG as floats: samples / 255 (or / 65535), grey replicated, alpha
// dropped, no transfer curve applied. `name` names the file in errors.
Image decode_png(const std::string& bytes, const std::string& name);

}  // namespace kdrt::detail
