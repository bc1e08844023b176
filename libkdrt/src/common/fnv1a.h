// FNV-1a, 64 bit: the one non-cryptographic hash libkdrt uses (tree-file
// checksums, scene-geometry fingerprints). Fast, byte-order independent as
// long as the caller feeds bytes in a fixed order.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kdrt::detail {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 0xcbf29ce484222325ull;

inline std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
        h ^= bytes[i];
        h *= 0x100000001b3ull;  // the FNV prime
    }
    return h;
}

}  // namespace kdrt::detail
