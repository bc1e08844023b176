#include "opencl/ray_order.h"

#include "device/kernel_records.h"

#include <algorithm>

namespace kdrt::detail {

namespace {

// Interleaves the bits of x and y (x in the even bits).
std::uint64_t morton2(std::uint32_t x, std::uint32_t y) {
    auto spread = [](std::uint64_t v) {
        v &= 0xFFFFFFFFull;
        v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
        v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
        v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
        v = (v | (v << 2)) & 0x3333333333333333ull;
        v = (v | (v << 1)) & 0x5555555555555555ull;
        return v;
    };
    return spread(x) | (spread(y) << 1);
}

}  // namespace

std::vector<std::uint32_t> pixel_order(int width, int height, RayOrder order) {
    const auto W = static_cast<std::uint32_t>(width), H = static_cast<std::uint32_t>(height);
    std::vector<std::uint32_t> out;
    out.reserve(static_cast<std::size_t>(W) * H);
    switch (order) {
        case RayOrder::Rows:
            for (std::uint32_t i = 0; i < W * H; ++i) out.push_back(i);
            break;
        case RayOrder::Tiles: {
            const std::uint32_t T = KDRT_PIXEL_TILE;
            for (std::uint32_t ty = 0; ty < H; ty += T)
                for (std::uint32_t tx = 0; tx < W; tx += T)
                    for (std::uint32_t y = ty; y < std::min(H, ty + T); ++y)
                        for (std::uint32_t x = tx; x < std::min(W, tx + T); ++x) out.push_back(y * W + x);
            break;
        }
        case RayOrder::Morton: {
            std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
            keyed.reserve(static_cast<std::size_t>(W) * H);
            for (std::uint32_t y = 0; y < H; ++y)
                for (std::uint32_t x = 0; x < W; ++x) keyed.emplace_back(morton2(x, y), y * W + x);
            std::sort(keyed.begin(), keyed.end());
            for (const auto& k : keyed) out.push_back(k.second);
            break;
        }
    }
    return out;
}

}  // namespace kdrt::detail
