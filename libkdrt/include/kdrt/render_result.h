// What a frame returns: the picture, the id map if asked for, what did not
// stop it, and its statistics (kdrt/render_stats.h).
#pragma once

#include <kdrt/image.h>
#include <kdrt/render_stats.h>

#include <cstdint>
#include <string>
#include <vector>

namespace kdrt {

struct RenderResult {
    Image image;
    std::vector<std::int32_t> ids;  // first sample's camera hit ids, -1 = none; if FrameOptions::want_ids
    std::vector<float> hit_t;       // their distances along the normalised ray
    std::vector<std::string> warnings;  // what did not stop the render: an unusable tree or kernel cache
    RenderStats stats;
};

}  // namespace kdrt
