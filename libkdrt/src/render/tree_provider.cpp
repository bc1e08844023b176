#include "render/tree_provider.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <chrono>
#include <cstdio>
#include <system_error>

namespace kdrt::detail {

namespace {

// Cache file name: the geometry fingerprint and every build parameter, so a
// changed scene or builder setting never picks up a stale tree.
std::filesystem::path cache_path(const std::filesystem::path& dir, const PreparedScene& scene,
                                 const KdBuildConfig& c) {
    char name[160];
    std::snprintf(name, sizeof name, "%016llx-%s-d%d-t%g-i%g-e%g-m%g.kdtree",
                  static_cast<unsigned long long>(scene.fingerprint), to_string(c.builder), c.max_depth,
                  c.traversal_cost, c.intersection_cost, c.empty_bonus, c.median_max_duplication);
    return dir / name;
}

}  // namespace

ProvidedTree provide_tree(const PreparedScene& scene, const RenderOptions& options) {
    ProvidedTree out;
    const auto start = std::chrono::steady_clock::now();
    std::optional<std::filesystem::path> cached;
    if (options.tree_cache_dir) cached = cache_path(*options.tree_cache_dir, scene, options.tree);

    if (options.load_tree) {
        out.tree = load_kd_tree(*options.load_tree, scene.fingerprint);
        out.loaded = true;
    } else if (cached && std::filesystem::exists(*cached)) {
        try {
            out.tree = load_kd_tree(*cached, scene.fingerprint);
            out.loaded = true;
        } catch (const Error&) {
            out.tree.reset();  // a damaged cache entry is rebuilt, not trusted
        }
    }
    if (!out.tree) {
        out.tree = build_kd_tree(scene.build_input(), options.tree);
        build_ropes(*out.tree);
        if (cached) {
            std::error_code ec;
            std::filesystem::create_directories(*options.tree_cache_dir, ec);
            if (ec)
                throw Error(ErrorCode::Io, options.tree_cache_dir->string() + ": cannot create the tree cache: " +
                                               ec.message());
            save_kd_tree(*cached, *out.tree, scene.fingerprint);
        }
    }
    if (!out.tree->has_ropes()) build_ropes(*out.tree);
    if (options.save_tree) save_kd_tree(*options.save_tree, *out.tree, scene.fingerprint);
    out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace kdrt::detail
