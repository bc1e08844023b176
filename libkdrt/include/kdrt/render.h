// Rendering a scene in one call: open the device, commit, render one frame.
// The options are those of the three steps (kdrt/device.h,
// kdrt/commit_options.h, kdrt/frame_options.h); the result is a frame's
// (kdrt/render_result.h).
#pragma once

#include <kdrt/commit_options.h>
#include <kdrt/export.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>
#include <kdrt/scene.h>

#include <filesystem>
#include <string>

namespace kdrt {

struct RenderOptions {
    std::string device;     // "cpu", "opencl", "opencl:N", ... (Device::open); empty: $KDRT_DEVICE or "cpu"
    CommitOptions commit;   // commit.progress reports the tree build and upload
    FrameOptions frame;     // frame.progress reports the frame
};

// Renders with the device named in options (throws kdrt::Error on bad input).
KDRT_API RenderResult render(const Scene& scene, const RenderOptions& options);

// Writes FORMAT.md's id map: W*H int32 ids then W*H float32 distances, little-endian.
KDRT_API void write_id_map(const std::filesystem::path& path, const RenderResult& result);

}  // namespace kdrt
