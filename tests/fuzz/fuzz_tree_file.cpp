// libFuzzer target: kd-tree files through kdrt::deserialize_kd_tree.
// A file's checksum would stop almost every mutation at the checksum test, so
// the checksum is recomputed over the input and the stored fingerprint is the
// expected one: the checks behind them (node links, leaf ranges, ropes, bounds)
// are what gets fuzzed. The header checks come before the checksum and are
// fuzzed as they are.
#include "common/xxh3.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace {

constexpr std::size_t kFingerprintOffset = 108;
constexpr std::size_t kChecksumOffset = 116;
constexpr std::size_t kHeaderSize = 124;

std::uint64_t read_u64(const std::uint8_t* p) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<std::uint8_t> bytes(data, data + size);
    std::uint64_t fingerprint = 0;
    if (size >= kHeaderSize) {
        fingerprint = read_u64(bytes.data() + kFingerprintOffset);
        kdrt::detail::Xxh3 hash;
        hash.update(bytes.data(), kChecksumOffset);
        hash.update(bytes.data() + kHeaderSize, size - kHeaderSize);
        const std::uint64_t h = hash.digest();
        for (int i = 0; i < 8; ++i) bytes[kChecksumOffset + i] = static_cast<std::uint8_t>(h >> (8 * i));
    }
    try {
        kdrt::deserialize_kd_tree(bytes.data(), bytes.size(), fingerprint, "fuzz.kdtree");
    } catch (const kdrt::Error&) {
    }
    return 0;
}
