// libFuzzer target: wide-BVH files through kdrt::deserialize_bvh, with the
// checksum recomputed (tree_file_input.h): the checks behind it (child
// indices, depth, leaf ranges, object ids, boxes) are what gets fuzzed. A
// loaded BVH is traversed, so that a check that lets a bad one through shows
// up as a sanitizer report or a failed KDRT_ASSERT.
#include "tree_file_input.h"

#include "bvh/bvh_io.h"
#include "cpu/traverse_bvh.h"

#include <kdrt/error.h>

#include <limits>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const TreeFileInput in = tree_file_input(data, size, {104, 112, 120});
    try {
        const kdrt::WideBvh bvh = kdrt::deserialize_bvh(in.bytes.data(), in.bytes.size(), in.fingerprint, "fuzz.bvh");
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
