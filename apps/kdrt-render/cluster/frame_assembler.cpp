#include "cluster/frame_assembler.h"

#include <kdrt/error.h>

#include <algorithm>

namespace kdrt::cluster {

std::optional<RenderResult> FrameAssembler::add(int frame, const PixelRect& rect, const RenderResult& tile) {
    const std::size_t pixels = static_cast<std::size_t>(rect.width) * static_cast<std::size_t>(rect.height);
    if (rect.x < 0 || rect.y < 0 || rect.width <= 0 || rect.height <= 0 || rect.x + rect.width > width_ ||
        rect.y + rect.height > height_ || tile.image.width != rect.width || tile.image.height != rect.height ||
        tile.image.rgb.size() != pixels * 3 || (want_ids_ && (tile.ids.size() != pixels || tile.hit_t.size() != pixels)))
        throw Error(ErrorCode::InvalidArgument, "cluster: a tile of frame " + std::to_string(frame) +
                                                    " does not fit its rectangle");
    auto [it, fresh] = frames_.try_emplace(frame);
    Partial& p = it->second;
    if (fresh) {
        p.result.image = Image(width_, height_);
        if (want_ids_) {
            p.result.ids.assign(static_cast<std::size_t>(width_) * height_, -1);
            p.result.hit_t.assign(static_cast<std::size_t>(width_) * height_, 0.0f);
        }
        p.pixels_left = static_cast<std::uint64_t>(width_) * static_cast<std::uint64_t>(height_);
    }
    for (int row = 0; row < rect.height; ++row) {
        const std::size_t from = static_cast<std::size_t>(row) * rect.width;
        const std::size_t to = static_cast<std::size_t>(rect.y + row) * width_ + rect.x;
        std::copy_n(tile.image.rgb.begin() + from * 3, rect.width * 3, p.result.image.rgb.begin() + to * 3);
        if (want_ids_) {
            std::copy_n(tile.ids.begin() + from, rect.width, p.result.ids.begin() + to);
            std::copy_n(tile.hit_t.begin() + from, rect.width, p.result.hit_t.begin() + to);
        }
    }
    p.result.stats.rays += tile.stats.rays;
    p.pixels_left -= std::min<std::uint64_t>(p.pixels_left, pixels);
    if (p.pixels_left != 0) return std::nullopt;
    RenderResult done = std::move(p.result);
    frames_.erase(it);
    return done;
}

}  // namespace kdrt::cluster
