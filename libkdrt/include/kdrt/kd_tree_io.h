// Binary serialization of kd-trees (format documented in src/kdtree/kd_tree_io.cpp).
#pragma once

#include <kdrt/export.h>
#include <kdrt/kd_tree.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt {

// The fingerprint ties a tree file to the scene geometry it was built for (the
// render uses an XXH3-64 of the scene's float geometry); a file with another
// fingerprint is refused. A file holds a tree with or without ropes, as given.
// Loading reads the arrays in bulk and runs check_kd_tree; a caller that has
// the scene should also run check_kd_tree_covers (the render does).
KDRT_API std::vector<std::uint8_t> serialize_kd_tree(const KdTree& tree, std::uint64_t geometry_fingerprint);
KDRT_API KdTree deserialize_kd_tree(const std::uint8_t* data, std::size_t size, std::uint64_t expected_fingerprint,
                                    const std::string& origin = "<memory>");

KDRT_API void save_kd_tree(const std::filesystem::path& path, const KdTree& tree, std::uint64_t geometry_fingerprint);
KDRT_API KdTree load_kd_tree(const std::filesystem::path& path, std::uint64_t expected_fingerprint);

}  // namespace kdrt
