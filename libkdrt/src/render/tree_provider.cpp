#include "render/tree_provider.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <glm/vector_relational.hpp>

#include <chrono>
#include <cstdio>
#include <system_error>

namespace kdrt::detail {

namespace {

// Bumped whenever the builders or the bounds they are given change, so that a
// cache never serves a tree built by older rules.
constexpr int kTreeRevision = 3;

// Cache file name: the geometry fingerprint, the builder revision and every
// build parameter, so a changed scene, builder or setting never picks up a
// stale tree.
std::filesystem::path cache_path(const std::filesystem::path& dir, const PreparedScene& scene,
                                 const KdBuildConfig& c) {
    char name[160];
    std::snprintf(name, sizeof name, "%016llx-r%d-%s-d%d-t%g-i%g-e%g-m%g.kdtree",
                  static_cast<unsigned long long>(scene.fingerprint), kTreeRevision, to_string(c.builder), c.max_depth,
                  c.traversal_cost, c.intersection_cost, c.empty_bonus, c.median_max_duplication);
    return dir / name;
}

// A loaded tree passed its own checks; it must also fit this scene: its ids
// index the scene's objects, and its box must hold them.
void check_fits(const KdTree& tree, const PreparedScene& scene, const std::string& origin) {
    const std::uint32_t objects = scene.geometry_d.object_count();
    if (tree.object_count != objects)
        throw Error(ErrorCode::CorruptTree, origin + ": the kd-tree indexes " + std::to_string(tree.object_count) +
                                                " objects, the scene has " + std::to_string(objects));
    if (!scene.bounds.empty() &&
        (tree.bounds.empty() || glm::any(glm::lessThan(scene.bounds.lo, tree.bounds.lo)) ||
         glm::any(glm::greaterThan(scene.bounds.hi, tree.bounds.hi))))
        throw Error(ErrorCode::CorruptTree, origin + ": the kd-tree's box does not contain the scene");
}

}  // namespace

ProvidedTree provide_tree(const PreparedScene& scene, const RenderOptions& options) {
    ProvidedTree out;
    const auto start = std::chrono::steady_clock::now();
    std::optional<std::filesystem::path> cached;
    if (options.tree_cache_dir) cached = cache_path(*options.tree_cache_dir, scene, options.tree);

    if (options.load_tree) {
        out.tree = load_kd_tree(*options.load_tree, scene.fingerprint);
        check_fits(*out.tree, scene, options.load_tree->string());
        out.loaded = true;
    } else if (cached && std::filesystem::exists(*cached)) {
        try {
            out.tree = load_kd_tree(*cached, scene.fingerprint);
            check_fits(*out.tree, scene, cached->string());
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
