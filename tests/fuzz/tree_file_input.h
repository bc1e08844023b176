// The fuzz input of a structure-file target (fuzz_tree_file, fuzz_bvh_file):
// a file's checksum would stop almost every mutation at the checksum test, so
// the input's checksum is recomputed, and its stored fingerprint is taken as
// the expected one. The header checks before the checksum are fuzzed as they are.
#pragma once

#include "common/tree_file_bytes.h"
#include "common/xxh3.h"

#include <cstddef>
#include <cstdint>
#include <vector>

struct TreeFileLayout {
    std::size_t fingerprint_offset, checksum_offset, header_size;
};

struct TreeFileInput {
    std::vector<std::uint8_t> bytes;
    std::uint64_t fingerprint = 0;
};

inline TreeFileInput tree_file_input(const std::uint8_t* data, std::size_t size, const TreeFileLayout& layout) {
    TreeFileInput in{std::vector<std::uint8_t>(data, data + size), 0};
    if (size < layout.header_size) return in;
    in.fingerprint = kdrt::detail::get_le(in.bytes.data() + layout.fingerprint_offset, 8);
    kdrt::detail::Xxh3 hash;
    hash.update(in.bytes.data(), layout.checksum_offset);
    hash.update(in.bytes.data() + layout.header_size, size - layout.header_size);
    const std::uint64_t h = hash.digest();
    for (int i = 0; i < 8; ++i) in.bytes[layout.checksum_offset + i] = static_cast<std::uint8_t>(h >> (8 * i));
    return in;
}
