#include "common/atomic_file.h"
#include "common/terminal_text.h"
#include "cpu/reference_renderer.h"
#include "scene/prepared_scene.h"
#include "kdtree/tree_provider.h"
#include "opencl/cl_devices.h"
#include "opencl/opencl_renderer.h"

#include <kdrt/error.h>
#include <kdrt/render.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdlib>

namespace kdrt {

RenderResult render(const Scene& scene, const RenderOptions& options) {
    std::string device = options.device;
    if (device.empty()) {
        const char* env = std::getenv("KDRT_DEVICE");
        device = (env && *env) ? env : "cpu";
    }
    std::string lower = device;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool opencl = lower == "opencl" || lower.rfind("opencl:", 0) == 0;
    if (lower == "cpu") device = lower;
    if (device != "cpu" && !opencl)
        throw Error(ErrorCode::Device, "unknown device '" + detail::escape_for_terminal(device) +
                                           "' (expected cpu, opencl or opencl:N; see --list-devices)");
    // Pick the device before the (possibly long) tree build, so a bad name fails fast.
    std::optional<detail::ocl::ClDevice> cl_device;
    if (opencl) cl_device = detail::ocl::select_device(device);
    const detail::PreparedScene prepared = detail::prepare_scene(scene, options);
    detail::ProvidedTree tree;
    // A tree given by file is always loaded and checked, even for Traversal::None.
    if (options.traversal != Traversal::None || options.build_tree || options.save_tree || options.load_tree)
        tree = detail::provide_tree(prepared, options);
    const KdTree* kd = tree.tree ? &*tree.tree : nullptr;
    RenderResult result = opencl ? detail::render_opencl(prepared, kd, options, *cl_device)
                                 : detail::render_reference(prepared, kd, options);
    result.build_ms = tree.build_ms;
    result.tree_loaded = tree.loaded;
    if (!tree.cache_warning.empty()) result.warnings.insert(result.warnings.begin(), tree.cache_warning);
    if (tree.tree) result.tree_stats = kd_tree_stats(*tree.tree, options.tree);
    return result;
}

void write_id_map(const std::filesystem::path& path, const RenderResult& result) {
    if (result.ids.empty() || result.ids.size() != result.hit_t.size())
        throw Error(ErrorCode::InvalidArgument, "write_id_map: the render has no id map (want_ids was off)");
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
