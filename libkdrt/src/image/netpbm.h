// PPM (binary P6, 8-bit) and PFM (Portable Float Map) files, written and read
// by hand: both are a text header and raw samples, exact and dependency-free.
// PFM: "PF" (RGB) or "Pf" (grey), "width height", a scale whose sign gives
// the byte order (negative: little-endian), then float rows bottom to top.
#pragma once

#include <kdrt/image.h>

#include <string>
#include <string_view>
#include <vector>

namespace kdrt::detail {

std::vector<unsigned char> encode_ppm(const unsigned char* rgb, int width, int height);
// Little-endian, scale -1; `rgb` rows top to bottom, as in kdrt::Image.
std::vector<unsigned char> encode_pfm(const float* rgb, int width, int height);

// Decodes P5/P6 (maxval up to 65535) and PF/Pf (either byte order); `name`
// names the file in errors (kdrt::Error(Io)).
Image decode_netpbm(std::string_view bytes, const std::string& name);

}  // namespace kdrt::detail
