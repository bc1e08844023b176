// Where a render's kd-tree comes from: a file (--load-tree), the tree cache
// (--tree-cache), or a fresh build; saved where asked (--save-tree).
#pragma once

#include "scene/prepared_scene.h"

#include <optional>

namespace kdrt::detail {

struct ProvidedTree {
    std::optional<KdTree> tree;
    double build_ms = 0.0;  // build, or load time when it came from a file
    bool loaded = false;
    std::string cache_warning;  // why the tree cache could not store the tree, or empty
};

ProvidedTree provide_tree(const PreparedScene& scene, const RenderOptions& options);

}  // namespace kdrt::detail
