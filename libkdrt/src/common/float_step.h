// One float step towards -inf or +inf, as std::nextafter(x, -+INFINITY) gives
// it, on the bits: the builders round every box outward this way, and the
// libm call was 3 % of a big mesh's build. x must not be NaN.
#pragma once

#include <bit>
#include <cstdint>
#include <limits>

namespace kdrt::detail {

inline float float_step_down(float x) {
    if (x == 0.0f) return -std::numeric_limits<float>::denorm_min();
    if (x == -std::numeric_limits<float>::infinity()) return x;
    const auto u = std::bit_cast<std::uint32_t>(x);
    return std::bit_cast<float>(x > 0.0f ? u - 1 : u + 1);
}

inline float float_step_up(float x) {
    if (x == 0.0f) return std::numeric_limits<float>::denorm_min();
    if (x == std::numeric_limits<float>::infinity()) return x;
    const auto u = std::bit_cast<std::uint32_t>(x);
    return std::bit_cast<float>(x > 0.0f ? u + 1 : u - 1);
}

}  // namespace kdrt::detail
