// Where a render's kd-tree comes from: a tree built in memory
// (RenderOptions::tree_in_memory, shared, not copied, unless ropes must be
// added), a file (--load-tree), the tree cache (--tree-cache), or a fresh
// build; saved where asked (--save-tree).
#pragma once

#include "scene/prepared_scene.h"

#include <memory>
#include <string>

namespace kdrt::detail {

struct ProvidedTree {
    std::shared_ptr<const KdTree> tree;
    double build_ms = 0.0;  // build, or load time when it came from a file
    bool loaded = false;        // from a file, the cache, or given in memory
    std::string cache_warning;  // why the tree cache could not store the tree, or empty
};

ProvidedTree provide_tree(const PreparedScene& scene, const RenderOptions& options);

}  // namespace kdrt::detail
