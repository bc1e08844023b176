// Rendering a scene: the one entry point that every device (the C++
// reference "cpu", OpenCL devices) goes through. Options and results are in
// render_options.h.
#pragma once

#include <kdrt/export.h>
#include <kdrt/render_options.h>

#include <filesystem>

namespace kdrt {

// Renders with the device named in options (throws kdrt::Error on bad input).
KDRT_API RenderResult render(const Scene& scene, const RenderOptions& options);

// Writes FORMAT.md's id map: W*H int32 ids then W*H float32 distances, little-endian.
KDRT_API void write_id_map(const std::filesystem::path& path, const RenderResult& result);

}  // namespace kdrt
