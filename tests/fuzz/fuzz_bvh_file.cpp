// libFuzzer target: wide-BVH files through kdrt::deserialize_bvh.
// A file's checksum would stop almost every mutation at the checksum test, so
// the checksum is recomputed over the input and the stored fingerprint is the
// expected one: the checks behind them (child indices, depth, leaf ranges,
// object ids, boxes) are what gets fuzzed. The header checks come before the
// checksum and are fuzzed as they are. A loaded BVH is traversed, so that a
// check that lets a bad one through shows up as a sanitizer report.
#include "bvh/bvh_io.h"
#include "common/xxh3.h"
#include "cpu/traverse_bvh.h"

#include <kdrt/error.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace {

constexpr std::size_t kFingerprintOffset = 104;
constexpr std::size_t kChecksumOffset = 112;
constexpr std::size_t kHeaderSize = 120;

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
        const kdrt::WideBvh bvh = kdrt::deserialize_bvh(bytes.data(), bytes.size(), fingerprint, "fuzz.bvh");
        std::uint64_t listed = 0;
        auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
            for (std::uint32_t i = 0; i < count; ++i) listed += ids[i];
            return std::numeric_limits<float>::infinity();
        };
        using kdrt::detail::Ray;
        for (const Ray<float>& ray : {Ray<float>({0, 0, 0}, {1, 0, 0}), Ray<float>({-1e3f, 0.5f, 0.25f}, {0.6f, 0.8f, 0.0f})})
            kdrt::detail::traverse_bvh(bvh, ray, std::numeric_limits<float>::infinity(), visit);
        if (listed == 1) return 0;  // keeps `listed` observable
    } catch (const kdrt::Error&) {
    }
    return 0;
}
