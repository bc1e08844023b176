// What both kd-tree builders share: rounding to float-representable values
// (splits and cells are stored as float, so every comparison the builders make
// must already be a comparison between floats), the root cell, and the leaf
// emission into the flat layout.
#pragma once

#include <kdrt/kd_tree.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

namespace kdrt::detail {

// Largest float <= v and smallest float >= v. Callers guarantee |v| <= FLT_MAX
// (kd_root_cell checks the input), so the conversions are defined.
inline float round_down_to_float(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}
inline float round_up_to_float(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

// The box rounded outward to float-representable values.
inline Aabb round_out_to_float(const Aabb& b) {
    Aabb r;
    for (int k = 0; k < 3; ++k) {
        r.lo[k] = round_down_to_float(b.lo[k]);
        r.hi[k] = round_up_to_float(b.hi[k]);
    }
    return r;
}

// Checks the input (at most 2^32-1 objects; every non-empty box finite and
// inside the float range: kdrt::Error(InvalidArgument) otherwise) and returns
// the root cell: the union of the non-empty boxes rounded outward to floats, or
// an empty Aabb when there is none. Objects with empty bounds are skipped.
Aabb kd_root_cell(const KdBuildInput& input);

// Appends a leaf node listing `ids` (sorted by the caller) to the tree.
void kd_emit_leaf(KdTree& tree, std::span<const std::uint32_t> ids);

}  // namespace kdrt::detail
