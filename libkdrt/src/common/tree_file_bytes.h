// The byte-level helpers of kdrt's structure files (kd-tree files,
// kdtree/kd_tree_io.cpp; BVH files, bvh/bvh_io.cpp): little-endian fields,
// arrays of 32-bit words copied in bulk and byte-swapped on big-endian hosts,
// overflow-safe size sums, and the error a corrupt file throws.
#pragma once

#include <kdrt/error.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace kdrt::detail {

inline constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;
static_assert(kLittleEndianHost || std::endian::native == std::endian::big, "mixed-endian hosts are not supported");

// Turns `bytes` bytes of 32-bit words between file order (little-endian) and host order, in place.
inline void swap_words_if_big_endian([[maybe_unused]] void* data, [[maybe_unused]] std::size_t bytes) {
    if constexpr (!kLittleEndianHost) {
        auto* p = static_cast<unsigned char*>(data);
        for (std::size_t i = 0; i < bytes; i += 4) {
            std::uint32_t w;
            std::memcpy(&w, p + i, 4);
            w = (w >> 24) | ((w >> 8) & 0xff00u) | ((w << 8) & 0xff0000u) | (w << 24);
            std::memcpy(p + i, &w, 4);
        }
    }
}

template <class T>
std::size_t byte_size(const std::vector<T>& v) {
    return v.size() * sizeof(T);
}

template <class T>
void swap_words_if_big_endian(std::vector<T>& v) {
    static_assert(sizeof(T) % 4 == 0, "structure files hold arrays of 32-bit words");
    swap_words_if_big_endian(v.data(), byte_size(v));
}

// Appends the `bytes` low bytes of v, least significant first.
inline void put_le(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

// Reads `bytes` bytes at p, least significant first.
inline std::uint64_t get_le(const std::uint8_t* p, int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= std::uint64_t{p[i]} << (8 * i);
    return v;
}

// acc += count * item_size; false on overflow.
inline bool add_array_size(std::uint64_t& acc, std::uint64_t count, std::uint64_t item_size) {
    if (count > (UINT64_MAX - acc) / item_size) return false;
    acc += count * item_size;
    return true;
}

inline std::string hex(std::uint64_t v) {
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

// Makes the Error (CorruptTree, naming the file) that a check of a structure file throws.
using TreeFileFail = std::function<Error(const std::string&)>;

}  // namespace kdrt::detail
