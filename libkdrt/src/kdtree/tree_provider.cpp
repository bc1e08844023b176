#include "kdtree/tree_provider.h"

#include "common/ms_since.h"
#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"
#include "bvh/bvh_io.h"
#include "kdtree/check_kd_tree_covers.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <glm/vector_relational.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <system_error>

namespace kdrt::detail {

namespace {

// Bumped whenever the builders or the bounds they are given change, so that a
// cache never serves a tree built by older rules.
constexpr int kTreeRevision = 6;  // 5: leaf nodes hold their list offset (file format 3); 6: bins per object
constexpr int kBvhRevision = 1;

// A save_kd_tree that was killed leaves its temporary file behind
// (detail::AtomicFile's ".<name>.tmp-XXXXXX"); one older than this can no
// longer be in the middle of being written.
constexpr auto kStaleTemporaryAge = std::chrono::minutes(10);

// ".<16 hex>-....kdtree.tmp-<6 alphanumerics>" (or .bvh.tmp-): only the
// temporaries of this cache's own entries, never another file of the directory.
bool is_cache_temporary(const std::string& name) {
    std::string mark = ".kdtree.tmp-";
    std::size_t at = name.rfind(mark);
    if (at == std::string::npos) at = name.rfind(mark = ".bvh.tmp-");
    if (name.size() < 18 || name[0] != '.' || name[17] != '-' || at == std::string::npos) return false;
    const std::string tail = name.substr(at + mark.size());
    auto hex = [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; };
    auto alnum = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; };
    return tail.size() == 6 && std::all_of(tail.begin(), tail.end(), alnum) &&
           std::all_of(name.begin() + 1, name.begin() + 17, hex);
}

// Removes the cache's stale temporary files. Best effort: another process may
// be cleaning up too, so errors are ignored.
void remove_stale_temporaries(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::directory_iterator it(dir, ec);
    if (ec) return;
    const auto now = std::filesystem::file_time_type::clock::now();
    for (; it != std::filesystem::directory_iterator(); it.increment(ec)) {
        if (ec) return;
        const std::filesystem::path p = it->path();
        if (!is_cache_temporary(p.filename().string()) || !it->is_regular_file(ec)) continue;
        const auto written = std::filesystem::last_write_time(p, ec);
        if (!ec && now - written > kStaleTemporaryAge) std::filesystem::remove(p, ec);
    }
}

// Cache file name: the geometry fingerprint, the builder revision and every
// build parameter, so a changed scene, builder or setting never picks up a
// stale tree.
std::filesystem::path cache_path(const std::filesystem::path& dir, const PreparedScene& scene,
                                 const KdBuildConfig& c) {
    char name[160];
    std::snprintf(name, sizeof name, "%016llx-r%d-%s-d%d-t%g-i%g-s%g-e%g-m%g-b%d-x%zu-u%g.kdtree",
                  static_cast<unsigned long long>(scene.fingerprint), kTreeRevision, to_string(c.builder), c.max_depth,
                  c.traversal_cost, c.intersection_cost, c.sphere_intersection_cost, c.empty_bonus,
                  c.median_max_duplication, c.sah_bins, c.exact_threshold, c.duplication_limit);
    return dir / name;
}

// A loaded tree passed its own checks; it must also fit this scene: its ids
// index the scene's objects, and its box must hold them.
void check_fits(const KdTree& tree, const PreparedScene& scene, const std::string& origin) {
    const std::uint32_t objects = scene.geometry_f.object_count();
    if (tree.object_count != objects)
        throw Error(ErrorCode::CorruptTree, origin + ": the kd-tree indexes " + std::to_string(tree.object_count) +
                                                " objects, the scene has " + std::to_string(objects));
    if (!scene.bounds.empty() &&
        (tree.bounds.empty() || glm::any(glm::lessThan(scene.bounds.lo, tree.bounds.lo)) ||
         glm::any(glm::greaterThan(scene.bounds.hi, tree.bounds.hi))))
        throw Error(ErrorCode::CorruptTree, origin + ": the kd-tree's box does not contain the scene");
    try {
        // Boxes only for the objects no leaf references: listing all of a big mesh's cost more than the load.
        check_kd_tree_covers(tree, [&](std::uint32_t id) { return scene.object_bound(id); });
    } catch (const Error& e) {
        throw Error(ErrorCode::CorruptTree, origin + ": " + e.what());
    }
}

// Writes a cache entry through `save`. The cache only saves time: a cache that
// cannot be written is reported (the returned warning), and the render goes on.
template <class Save>
std::string store_in_cache(const std::filesystem::path& dir, Save&& save) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    try {
        if (ec) throw Error(ErrorCode::Io, dir.string() + ": cannot create: " + ec.message());
        save();
    } catch (const Error& e) {
        return std::string("tree cache: ") + e.what() + "; rendering without it";
    }
    return {};
}

std::filesystem::path bvh_cache_path(const std::filesystem::path& dir, const PreparedScene& scene,
                                     const BvhBuildConfig& c) {
    char name[160];
    std::snprintf(name, sizeof name, "%016llx-r%d-bvh%d-b%d-l%d-t%g-i%g-s%g-k%d.bvh",
                  static_cast<unsigned long long>(scene.fingerprint), kBvhRevision, kWideBvhWidth, c.bins,
                  c.max_leaf_size, c.traversal_cost, c.intersection_cost, c.sphere_intersection_cost, c.leaf_block);
    return dir / name;
}

// A loaded BVH passed its own checks; it must also fit this scene: every
// object with a box in a leaf whose box holds it.
void check_bvh_fits(const WideBvh& bvh, const PreparedScene& scene, const std::string& origin) {
    const std::uint32_t objects = scene.geometry_f.object_count();
    if (bvh.object_count != objects)
        throw Error(ErrorCode::CorruptTree, origin + ": the BVH indexes " + std::to_string(bvh.object_count) +
                                                " objects, the scene has " + std::to_string(objects));
    try {
        check_bvh(bvh, scene.object_bounds());
    } catch (const Error& e) {
        throw Error(ErrorCode::CorruptTree, origin + ": " + e.what());
    }
}

// A loaded BVH that fits, or nothing for a damaged cache entry (rebuilt, not trusted).
std::optional<WideBvh> load_fitting_bvh(const std::filesystem::path& path, const PreparedScene& scene, bool cache) {
    try {
        WideBvh bvh = load_bvh(path, scene.fingerprint);
        check_bvh_fits(bvh, scene, path.string());
        return bvh;
    } catch (const Error&) {
        if (!cache) throw;
        return std::nullopt;
    }
}

}  // namespace

ProvidedBvh provide_bvh(const PreparedScene& scene, const CommitOptions& options) {
    if (options.tree_files.in_memory)
        throw Error(ErrorCode::InvalidArgument,
                    "TreeFiles::in_memory holds a kd-tree: a commit with Accel::Bvh cannot use it");
    ProvidedBvh out;
    const auto start = std::chrono::steady_clock::now();
    std::optional<std::filesystem::path> cached;
    if (options.tree_files.cache_dir) {
        cached = bvh_cache_path(*options.tree_files.cache_dir, scene, options.bvh);
        remove_stale_temporaries(*options.tree_files.cache_dir);
    }
    std::optional<WideBvh> bvh;
    if (options.tree_files.load) {
        bvh = load_fitting_bvh(*options.tree_files.load, scene, false);
    } else if (std::error_code exists_ec; cached && std::filesystem::exists(*cached, exists_ec)) {
        bvh = load_fitting_bvh(*cached, scene, true);
    }
    out.loaded = bvh.has_value();
    if (!bvh) {
        const std::vector<Aabb> bounds = scene.object_bounds();
        bvh = build_wide_bvh(BvhBuildInput{bounds, static_cast<std::uint32_t>(scene.geometry_f.spheres.size())},
                             options.bvh);
        if (cached)
            out.cache_warning = store_in_cache(*options.tree_files.cache_dir,
                                               [&] { save_bvh(*cached, *bvh, scene.fingerprint); });
    }
    out.bvh = std::make_shared<WideBvh>(std::move(*bvh));
    if (options.tree_files.save) save_bvh(*options.tree_files.save, *out.bvh, scene.fingerprint);
    out.build_ms = ms_since(start);
    return out;
}

ProvidedTree provide_tree(const PreparedScene& scene, const CommitOptions& options) {
    ProvidedTree out;
    const auto start = std::chrono::steady_clock::now();
    std::optional<std::filesystem::path> cached;
    if (options.tree_files.cache_dir && !options.tree_files.in_memory) {
        cached = cache_path(*options.tree_files.cache_dir, scene, options.tree);
        remove_stale_temporaries(*options.tree_files.cache_dir);
    }

    std::optional<KdTree> tree;
    if (options.tree_files.in_memory) {
        // Checked like a loaded tree: a tree of other geometry is refused, never traced.
        const std::string origin = "TreeFiles::in_memory";
        try {
            check_kd_tree(*options.tree_files.in_memory);
        } catch (const Error& e) {
            throw Error(ErrorCode::CorruptTree, origin + ": " + e.what());
        }
        check_fits(*options.tree_files.in_memory, scene, origin);
        out.loaded = true;
        if (options.traversal == Traversal::Ropes && !options.tree_files.in_memory->has_ropes())
            tree = *options.tree_files.in_memory;  // a copy gets the ropes
        else
            out.tree = options.tree_files.in_memory;
    } else if (options.tree_files.load) {
        tree = load_kd_tree(*options.tree_files.load, scene.fingerprint);
        check_fits(*tree, scene, options.tree_files.load->string());
        out.loaded = true;
    } else if (std::error_code exists_ec; cached && std::filesystem::exists(*cached, exists_ec)) {
        try {
            tree = load_kd_tree(*cached, scene.fingerprint);
            check_fits(*tree, scene, cached->string());
            out.loaded = true;
        } catch (const Error&) {
            tree.reset();  // a damaged cache entry is rebuilt, not trusted
        }
    }
    if (!tree && !out.tree) {
        tree = build_kd_tree(scene.build_input(), options.tree);
        // Cached without ropes: they are quick to rebuild, and most traversals need none.
        if (cached)
            out.cache_warning = store_in_cache(*options.tree_files.cache_dir,
                                               [&] { save_kd_tree(*cached, *tree, scene.fingerprint); });
    }
    if (tree) {
        // Ropes cost 48 bytes a leaf, more than the rest of the tree: only the
        // ropes traversal gets them, built here if the tree came without.
        if (options.traversal == Traversal::Ropes) {
            if (!tree->has_ropes()) build_ropes(*tree);
        } else {
            std::vector<KdLeafRopes>().swap(tree->ropes);
        }
        out.tree = std::make_shared<const KdTree>(std::move(*tree));
    }
    if (options.tree_files.save) save_kd_tree(*options.tree_files.save, *out.tree, scene.fingerprint);
    out.build_ms = ms_since(start);
    return out;
}

}  // namespace kdrt::detail
