// Where a commit's kd-tree or BVH comes from: a tree built in memory
// (TreeFiles::in_memory, shared, not copied, unless ropes must be added), a
// file (TreeFiles::load), the tree cache (TreeFiles::cache_dir), or a fresh
// build; saved where asked (TreeFiles::save).
#pragma once

#include "bvh/bvh.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>

#include <memory>
#include <string>

namespace kdrt::detail {

struct ProvidedTree {
    std::shared_ptr<const KdTree> tree;
    double build_ms = 0.0;  // build, or load time when it came from a file
    bool loaded = false;        // from a file, the cache, or given in memory
    std::string cache_warning;  // why the tree cache could not store the tree, or empty
};

ProvidedTree provide_tree(const PreparedScene& scene, const CommitOptions& options);

// The same for a BVH (Accel::Bvh): a file (TreeFiles::load, refused when it
// holds a kd-tree), the cache, or a build with options.bvh; TreeFiles::in_memory
// (a kd-tree) is refused. Mutable: CommittedScene::update() refits it.
struct ProvidedBvh {
    std::shared_ptr<WideBvh> bvh;
    double build_ms = 0.0;
    bool loaded = false;
    std::string cache_warning;
};

ProvidedBvh provide_bvh(const PreparedScene& scene, const CommitOptions& options);

}  // namespace kdrt::detail
