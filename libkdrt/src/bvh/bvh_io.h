// Binary wide-BVH files (format documented in bvh_io.cpp), in the tree-file
// framework of the kd-tree's (kd_tree_io.h): versioned, XXH3-checksummed, tied
// to the geometry by its fingerprint, checked on load.
#pragma once

#include "bvh/bvh.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt {

// A file with another fingerprint, another width than N, or the other kind of
// tree is refused with a kdrt::Error(CorruptTree) that says so. Loading reads
// the arrays in bulk and runs check_bvh; a caller that has the scene should
// also run check_bvh(bvh, object_bounds), which finds objects left out.
template <int N>
std::vector<std::uint8_t> serialize_bvh(const WideBvhN<N>& bvh, std::uint64_t geometry_fingerprint);
template <int N = kWideBvhWidth>
WideBvhN<N> deserialize_bvh(const std::uint8_t* data, std::size_t size, std::uint64_t expected_fingerprint,
                            const std::string& origin = "<memory>");

template <int N>
void save_bvh(const std::filesystem::path& path, const WideBvhN<N>& bvh, std::uint64_t geometry_fingerprint);
template <int N = kWideBvhWidth>
WideBvhN<N> load_bvh(const std::filesystem::path& path, std::uint64_t expected_fingerprint);

extern template std::vector<std::uint8_t> serialize_bvh<4>(const WideBvhN<4>&, std::uint64_t);
extern template std::vector<std::uint8_t> serialize_bvh<8>(const WideBvhN<8>&, std::uint64_t);
extern template WideBvhN<4> deserialize_bvh<4>(const std::uint8_t*, std::size_t, std::uint64_t, const std::string&);
extern template WideBvhN<8> deserialize_bvh<8>(const std::uint8_t*, std::size_t, std::uint64_t, const std::string&);
extern template void save_bvh<4>(const std::filesystem::path&, const WideBvhN<4>&, std::uint64_t);
extern template void save_bvh<8>(const std::filesystem::path&, const WideBvhN<8>&, std::uint64_t);
extern template WideBvhN<4> load_bvh<4>(const std::filesystem::path&, std::uint64_t);
extern template WideBvhN<8> load_bvh<8>(const std::filesystem::path&, std::uint64_t);

}  // namespace kdrt
