#include "common/atomic_file.h"
#include "render/committed_scene_state.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/render.h>

#include <bit>

namespace kdrt {

// One call: open the device, commit for the frame's depth (nothing is
// compiled twice), render the frame (which reports the commit's build,
// compile and upload).
RenderResult render(const Scene& scene, const RenderOptions& options) {
    const Device device = Device::open(options.device);
    return detail::CommittedSceneAccess::commit(device, scene, options.commit, options.frame).render(options.frame);
}

void write_id_map(const std::filesystem::path& path, const RenderResult& result) {
    if (result.ids.empty() || result.ids.size() != result.hit_t.size())
        throw Error(ErrorCode::InvalidArgument, "write_id_map: the render has no id map (FrameOptions::want_ids was off)");
    std::vector<unsigned char> bytes;
    bytes.reserve(result.ids.size() * 8);
    auto put = [&](std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<unsigned char>(v >> (8 * i)));
    };
    for (std::int32_t id : result.ids) put(static_cast<std::uint32_t>(id));
    for (float t : result.hit_t) put(std::bit_cast<std::uint32_t>(t));
    detail::write_file_atomically(path, bytes);
}

}  // namespace kdrt
