// kdrt's tree files begin with an 8-byte magic: "KDRT" and the kind of tree
// ("TREE": a kd-tree, kdtree/kd_tree_io.cpp; "WBVH": a wide BVH,
// bvh/bvh_io.cpp). Each reader names the other kind when it is given one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace kdrt::detail {

inline constexpr char kKdTreeFileMagic[8] = {'K', 'D', 'R', 'T', 'T', 'R', 'E', 'E'};
inline constexpr char kWideBvhFileMagic[8] = {'K', 'D', 'R', 'T', 'W', 'B', 'V', 'H'};

enum class TreeFileKind { Unknown, KdTree, WideBvh };

// The kind named by a file's first bytes (Unknown for fewer than 8).
inline TreeFileKind tree_file_kind(const std::uint8_t* data, std::size_t size) {
    if (size < 8) return TreeFileKind::Unknown;
    if (std::memcmp(data, kKdTreeFileMagic, 8) == 0) return TreeFileKind::KdTree;
    if (std::memcmp(data, kWideBvhFileMagic, 8) == 0) return TreeFileKind::WideBvh;
    return TreeFileKind::Unknown;
}

}  // namespace kdrt::detail
