// libFuzzer target: scene wire bytes (kdrt/scene_wire.h) through
// kdrt::deserialize_scene. As for tree files, the checksum would stop almost
// every mutation, so the payload size and the checksum are made to match the
// input: the checks behind them (counts against the bytes left, strings,
// `added` kinds, validate and the object ids) are what gets fuzzed. The magic
// and version checks come before and are fuzzed as they are.
#include "common/xxh3.h"

#include <kdrt/error.h>
#include <kdrt/scene_wire.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace {

constexpr std::size_t kPayloadSizeOffset = 12;
constexpr std::size_t kChecksumOffset = 20;
constexpr std::size_t kHeaderSize = 28;

void put_u64(std::uint8_t* p, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<std::uint8_t> bytes(data, data + size);
    if (size >= kHeaderSize) {
        put_u64(bytes.data() + kPayloadSizeOffset, size - kHeaderSize);
        kdrt::detail::Xxh3 hash;
        hash.update(bytes.data(), kChecksumOffset);
        hash.update(bytes.data() + kHeaderSize, size - kHeaderSize);
        put_u64(bytes.data() + kChecksumOffset, hash.digest());
    }
    try {
        kdrt::deserialize_scene(bytes.data(), bytes.size(), "fuzz.scene");
    } catch (const kdrt::Error&) {
    }
    return 0;
}
