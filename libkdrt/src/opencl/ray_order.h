// The order in which camera rays are issued: rows, 8x8 screen tiles, or a
// Morton (Z-order) curve, so neighbouring work-items trace neighbouring pixels.
#pragma once

#include <kdrt/render_options.h>

#include <cstdint>
#include <vector>

namespace kdrt::detail {

// A permutation of 0 .. width*height-1 (pixel = y * width + x).
std::vector<std::uint32_t> pixel_order(int width, int height, RayOrder order);

}  // namespace kdrt::detail
