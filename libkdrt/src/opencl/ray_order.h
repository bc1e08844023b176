// The order in which camera rays are issued: rows, 8x8 screen tiles, or a
// Morton (Z-order) curve, so neighbouring work-items trace neighbouring pixels.
// A GPU's frame kernel computes rows and tiles itself (pixel_at in render.cl);
// a Morton order, and every order on CPU devices, is uploaded as this table.
#pragma once

#include <kdrt/frame_options.h>

#include <cstdint>
#include <vector>

namespace kdrt::detail {

// A permutation of 0 .. width*height-1 (pixel = y * width + x).
std::vector<std::uint32_t> pixel_order(int width, int height, RayOrder order);

}  // namespace kdrt::detail
