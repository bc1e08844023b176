#include "cpu/reference_renderer.h"
#include "render/prepared_scene.h"
#include "render/tree_provider.h"

#include <kdrt/error.h>
#include <kdrt/render.h>

#include <bit>
#include <fstream>

namespace kdrt {

const char* to_string(Traversal t) {
    switch (t) {
        case Traversal::None: return "none";
        case Traversal::Restart: return "restart";
        case Traversal::Ropes: return "ropes";
        case Traversal::Stack: return "stack";
    }
    return "?";
}

Traversal traversal_from_string(const std::string& name) {
    for (Traversal t : {Traversal::None, Traversal::Restart, Traversal::Ropes, Traversal::Stack})
        if (name == to_string(t)) return t;
    throw Error(ErrorCode::InvalidArgument, "unknown traversal '" + name + "' (expected none, restart, ropes or stack)");
}

const char* to_string(Precision p) { return p == Precision::Double ? "double" : "float"; }

Precision precision_from_string(const std::string& name) {
    if (name == "float") return Precision::Float;
    if (name == "double") return Precision::Double;
    throw Error(ErrorCode::InvalidArgument, "unknown precision '" + name + "' (expected float or double)");
}

RenderResult render(const Scene& scene, const RenderOptions& options) {
    const detail::PreparedScene prepared = detail::prepare_scene(scene, options);
    if (options.device != "cpu")
        throw Error(ErrorCode::Device, "unknown device '" + options.device + "' (see --list-devices)");
    detail::ProvidedTree tree;
    if (options.traversal != Traversal::None) tree = detail::provide_tree(prepared, options);
    RenderResult result = detail::render_reference(prepared, tree.tree ? &*tree.tree : nullptr, options);
    result.build_ms = tree.build_ms;
    result.tree_loaded = tree.loaded;
    if (tree.tree) result.tree_stats = kd_tree_stats(*tree.tree, options.tree);
    return result;
}

void write_id_map(const std::filesystem::path& path, const RenderResult& result) {
    if (result.ids.size() != result.hit_t.size())
        throw Error(ErrorCode::InvalidArgument, "write_id_map: the render has no id map (want_ids was off)");
    std::vector<unsigned char> bytes;
    bytes.reserve(result.ids.size() * 8);
    auto put = [&](std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<unsigned char>(v >> (8 * i)));
    };
    for (std::int32_t id : result.ids) put(static_cast<std::uint32_t>(id));
    for (float t : result.hit_t) put(std::bit_cast<std::uint32_t>(t));
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw Error(ErrorCode::Io, path.string() + ": cannot write the id map");
}

}  // namespace kdrt
