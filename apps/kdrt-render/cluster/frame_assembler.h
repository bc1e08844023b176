// Rank 0's frames being put together from tiles: a frame-sized image (and id
// map) per frame in flight, made on its first tile and handed out once every
// pixel has arrived.
#pragma once

#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>

#include <map>
#include <optional>

namespace kdrt::cluster {

class FrameAssembler {
public:
    FrameAssembler(int width, int height, bool want_ids) : width_(width), height_(height), want_ids_(want_ids) {}

    // Copies a tile's region-sized result into its frame; returns the frame
    // once it is complete (rays summed over its tiles). Throws
    // kdrt::Error(InvalidArgument) for a tile outside the frame or of the wrong size.
    std::optional<RenderResult> add(int frame, const PixelRect& rect, const RenderResult& tile);

private:
    struct Partial {
        RenderResult result;
        std::uint64_t pixels_left = 0;
    };
    int width_, height_;
    bool want_ids_;
    std::map<int, Partial> frames_;
};

}  // namespace kdrt::cluster
