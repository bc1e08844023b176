// Forging kd-trees for the tests that check the loaders refuse them.
#pragma once

#include <kdrt/kd_tree.h>
#include <kdrt/kd_tree_io.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include <cstdint>
#include <vector>

namespace kdrt::test {

// A saved tree file read back with the fingerprint it names (header offset
// 108), so a test can alter the tree and save it as a forger would.
struct SavedTree {
    KdTree tree;
    std::uint64_t fingerprint = 0;
};

inline SavedTree read_saved_tree(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SavedTree saved;
    for (int i = 0; i < 8 && 108 + i < static_cast<int>(bytes.size()); ++i)
        saved.fingerprint |= std::uint64_t{bytes[static_cast<std::size_t>(108 + i)]} << (8 * i);
    saved.tree = deserialize_kd_tree(bytes.data(), bytes.size(), saved.fingerprint);
    return saved;
}

// Removes every reference to object `id` from the leaves, keeping the tree
// structurally sound: what a forger who wants an object to vanish would do.
// Returns how many references were removed.
inline std::size_t drop_object(KdTree& tree, std::uint32_t id) {
    std::vector<std::uint32_t> kept;
    for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
        if (!kd_is_leaf(tree.nodes[i])) continue;
        const std::uint32_t begin = kd_leaf_first(tree.nodes[i]), end = begin + kd_leaf_count(tree.nodes[i]);
        const auto first = static_cast<std::uint32_t>(kept.size());
        for (std::uint32_t j = begin; j < end; ++j)
            if (tree.leaf_objects[j] != id) kept.push_back(tree.leaf_objects[j]);
        tree.nodes[i] = kd_make_leaf(first, static_cast<std::uint32_t>(kept.size()) - first);
    }
    const std::size_t removed = tree.leaf_objects.size() - kept.size();
    tree.leaf_objects = std::move(kept);
    return removed;
}

}  // namespace kdrt::test
