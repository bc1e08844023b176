// Wide-BVH files.
//
// Format, version 1. Integers are little-endian; floats are their IEEE-754 bit
// patterns (binary32 / binary64) stored as little-endian integers; no padding.
// The header is written and read field by field; the arrays, all made of
// 32-bit words, are copied in bulk (each word byte-swapped on a big-endian host).
//
//   offset size  field
//        0    8  magic "KDRTWBVH" (ASCII; a kd-tree file has "KDRTTREE": common/tree_file_kind.h)
//        8    4  u32 format version = 1
//       12    4  u32 width N: children per node, 4 or 8
//       16    4  u32 object_count       objects the BVH was built over
//       20    4  u32 reserved = 0
//       24    8  u64 node_count         >= 1
//       32    8  u64 leaf_object_count  <= object_count
//       40   48  f64 bounds             lo.x lo.y lo.z hi.x hi.y hi.z
//       88    8  f64 build_sah_cost     finite, >= 1
//       96    8  u64 payload_size       = 32 N node_count + 4 leaf_object_count
//      104    8  u64 geometry fingerprint (see bvh_io.h)
//      112    8  u64 checksum           XXH3-64 (seed 0) of bytes [0, 112)
//                                         followed by the payload: every byte but itself
//      120       payload, in this order:
//                  nodes         node_count x (f32 box[2][3][N], u32 child[N], u32 count[N]),
//                                              as WideBvhNodeN (bvh.h) lays them out
//                  leaf objects  leaf_object_count x u32 object id
//
// The file is exactly 120 + payload_size bytes. XXH3 is not a cryptographic
// hash, so the checksum catches damage, not forgery: a forged file with a
// recomputed checksum still has to pass check_bvh (every index in range, no
// cycles, depth, boxes enclosing their children, each object listed once) and,
// against its scene, check_bvh with the objects' boxes. Loading checks, in
// order: magic (naming a kd-tree file as such), version, width, the counts and
// sizes against the file's length (overflow-safe), checksum, fingerprint,
// then check_bvh on the decoded BVH.
#include "bvh/bvh_io.h"

#include "bvh/bvh_check.h"
#include "common/atomic_file.h"
#include "common/tree_file_bytes.h"
#include "common/tree_file_kind.h"
#include "common/xxh3.h"

#include <kdrt/error.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <system_error>

namespace kdrt {

namespace {

constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kChecksumOffset = 112;
constexpr std::size_t kHeaderSize = 120;

static_assert(sizeof(WideBvhNodeN<8>) % 4 == 0 && sizeof(WideBvhNodeN<4>) % 4 == 0);

using detail::byte_size;
using detail::hex;
using detail::swap_words_if_big_endian;
using Fail = detail::TreeFileFail;
using detail::get_le;
using detail::put_le;

struct Header {
    std::uint32_t width = 0, object_count = 0;
    std::uint64_t node_count = 0, leaf_object_count = 0;
    Aabb bounds;
    double build_sah_cost = 0.0;
    std::uint64_t fingerprint = 0, checksum = 0;
};

// Decodes and checks the header of a file of `file_size` bytes whose first
// min(file_size, kHeaderSize) bytes are at `data`.
template <int N>
Header read_header(const std::uint8_t* data, std::uint64_t file_size, const Fail& fail) {
    const std::size_t have = static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kHeaderSize));
    if (file_size == 0) throw fail("empty file, not a BVH");
    if (detail::tree_file_kind(data, have) == detail::TreeFileKind::KdTree)
        throw fail("is a kd-tree file, not a BVH file: load it as a kd-tree (Accel::KdTree, kdrt-render --accel kd), "
                   "or build a BVH");
    if (std::memcmp(data, detail::kWideBvhFileMagic, std::min<std::size_t>(have, 8)) != 0)
        throw fail("not a kdrt BVH file (bad magic)");
    if (have < 16) throw fail("truncated BVH file: " + std::to_string(file_size) + " bytes, no version and width");
    const auto version = static_cast<std::uint32_t>(get_le(data + 8, 4));
    if (version > kVersion)
        throw fail("BVH file format version " + std::to_string(version) + " is newer than this build reads (" +
                   std::to_string(kVersion) + "); rebuild the BVH");
    if (version != kVersion) throw fail("unknown BVH file format version " + std::to_string(version));
    Header h;
    h.width = static_cast<std::uint32_t>(get_le(data + 12, 4));
    if (h.width != static_cast<std::uint32_t>(N))
        throw fail("BVH file of width " + std::to_string(h.width) + ", where " + std::to_string(N) +
                   " children per node are expected; rebuild the BVH");
    if (have < kHeaderSize)
        throw fail("truncated BVH file: " + std::to_string(file_size) + " bytes, shorter than the " +
                   std::to_string(kHeaderSize) + "-byte header");
    h.object_count = static_cast<std::uint32_t>(get_le(data + 16, 4));
    const std::uint64_t reserved = get_le(data + 20, 4);
    h.node_count = get_le(data + 24, 8);
    h.leaf_object_count = get_le(data + 32, 8);
    for (int k = 0; k < 3; ++k) h.bounds.lo[k] = std::bit_cast<double>(get_le(data + 40 + 8 * k, 8));
    for (int k = 0; k < 3; ++k) h.bounds.hi[k] = std::bit_cast<double>(get_le(data + 64 + 8 * k, 8));
    h.build_sah_cost = std::bit_cast<double>(get_le(data + 88, 8));
    const std::uint64_t payload_size = get_le(data + 96, 8);
    h.fingerprint = get_le(data + 104, 8);
    h.checksum = get_le(data + 112, 8);

    if (reserved != 0) throw fail("reserved header field (offset 20) is " + std::to_string(reserved) + ", not 0");
    if (h.node_count == 0 || h.node_count > 0xFFFFFFFFull)
        throw fail("node count " + std::to_string(h.node_count) + " is out of range");
    if (h.leaf_object_count > h.object_count)
        throw fail("leaf object count " + std::to_string(h.leaf_object_count) + " exceeds the object count " +
                   std::to_string(h.object_count));
    if (!(std::isfinite(h.build_sah_cost) && h.build_sah_cost >= 1.0))
        throw fail("build SAH cost " + std::to_string(h.build_sah_cost) + " is not a finite value >= 1");
    // Both counts are below 2^32: the sum cannot overflow 64 bits.
    const std::uint64_t expected_payload = h.node_count * sizeof(WideBvhNodeN<N>) + 4 * h.leaf_object_count;
    if (payload_size != expected_payload)
        throw fail("payload size " + std::to_string(payload_size) + " does not match the counts (" +
                   std::to_string(expected_payload) + ")");
    if (payload_size != file_size - kHeaderSize)
        throw fail("file has " + std::to_string(file_size - kHeaderSize) + " payload bytes, the header announces " +
                   std::to_string(payload_size) + (file_size - kHeaderSize < payload_size ? " (truncated)" : ""));
    return h;
}

template <int N>
WideBvhN<N> sized_bvh(const Header& h) {
    WideBvhN<N> bvh;
    bvh.object_count = h.object_count;
    bvh.bounds = h.bounds;
    bvh.build_sah_cost = h.build_sah_cost;
    bvh.nodes.resize(h.node_count);
    bvh.leaf_objects.resize(h.leaf_object_count);
    return bvh;
}

// Checks the checksum (of the arrays still in file byte order), the
// fingerprint and the structure, and brings the arrays into host order.
template <int N>
WideBvhN<N> finish(WideBvhN<N> bvh, const Header& h, std::uint64_t actual_checksum,
                   std::uint64_t expected_fingerprint, const Fail& fail) {
    if (h.checksum != actual_checksum)
        throw fail("checksum mismatch (stored " + hex(h.checksum) + ", computed " + hex(actual_checksum) + ")");
    if (h.fingerprint != expected_fingerprint)
        throw fail("the BVH was built for different geometry (fingerprint " + hex(h.fingerprint) + ", expected " +
                   hex(expected_fingerprint) + "); rebuild it");
    swap_words_if_big_endian(bvh.nodes.data(), byte_size(bvh.nodes));
    swap_words_if_big_endian(bvh.leaf_objects.data(), byte_size(bvh.leaf_objects));
    try {
        check_bvh(bvh);
    } catch (const Error& e) {
        throw fail(e.what());
    }
    return bvh;
}

}  // namespace

template <int N>
std::vector<std::uint8_t> serialize_bvh(const WideBvhN<N>& bvh, std::uint64_t geometry_fingerprint) {
    const std::uint64_t payload = byte_size(bvh.nodes) + byte_size(bvh.leaf_objects);
    std::vector<std::uint8_t> out;
    out.reserve(kHeaderSize + payload);
    for (char c : detail::kWideBvhFileMagic) out.push_back(static_cast<std::uint8_t>(c));
    put_le(out, kVersion, 4);
    put_le(out, N, 4);
    put_le(out, bvh.object_count, 4);
    put_le(out, 0, 4);  // reserved
    put_le(out, bvh.nodes.size(), 8);
    put_le(out, bvh.leaf_objects.size(), 8);
    for (int k = 0; k < 3; ++k) put_le(out, std::bit_cast<std::uint64_t>(bvh.bounds.lo[k]), 8);
    for (int k = 0; k < 3; ++k) put_le(out, std::bit_cast<std::uint64_t>(bvh.bounds.hi[k]), 8);
    put_le(out, std::bit_cast<std::uint64_t>(bvh.build_sah_cost), 8);
    put_le(out, payload, 8);
    put_le(out, geometry_fingerprint, 8);
    put_le(out, 0, 8);  // checksum, filled in below
    const std::size_t nodes_at = out.size();
    out.resize(out.size() + payload);
    if (!bvh.nodes.empty()) std::memcpy(out.data() + nodes_at, bvh.nodes.data(), byte_size(bvh.nodes));
    if (!bvh.leaf_objects.empty())
        std::memcpy(out.data() + nodes_at + byte_size(bvh.nodes), bvh.leaf_objects.data(), byte_size(bvh.leaf_objects));
    swap_words_if_big_endian(out.data() + nodes_at, payload);
    detail::Xxh3 hash;
    hash.update(out.data(), kChecksumOffset);
    hash.update(out.data() + kHeaderSize, out.size() - kHeaderSize);
    const std::uint64_t checksum = hash.digest();
    for (int i = 0; i < 8; ++i) out[kChecksumOffset + i] = static_cast<std::uint8_t>(checksum >> (8 * i));
    return out;
}

template <int N>
WideBvhN<N> deserialize_bvh(const std::uint8_t* data, std::size_t size, std::uint64_t expected_fingerprint,
                            const std::string& origin) {
    const Fail fail = [&](const std::string& what) { return Error(ErrorCode::CorruptTree, origin + ": " + what); };
    const Header h = read_header<N>(data, size, fail);
    WideBvhN<N> bvh = sized_bvh<N>(h);
    detail::Xxh3 hash;
    hash.update(data, kChecksumOffset);
    hash.update(data + kHeaderSize, size - kHeaderSize);
    std::memcpy(bvh.nodes.data(), data + kHeaderSize, byte_size(bvh.nodes));
    if (!bvh.leaf_objects.empty())
        std::memcpy(bvh.leaf_objects.data(), data + kHeaderSize + byte_size(bvh.nodes), byte_size(bvh.leaf_objects));
    return finish<N>(std::move(bvh), h, hash.digest(), expected_fingerprint, fail);
}

template <int N>
void save_bvh(const std::filesystem::path& path, const WideBvhN<N>& bvh, std::uint64_t geometry_fingerprint) {
    const std::vector<std::uint8_t> bytes = serialize_bvh(bvh, geometry_fingerprint);
    // Written beside the target and renamed over it: readers never see half a file.
    detail::write_file_atomically(path, bytes);
}

template <int N>
WideBvhN<N> load_bvh(const std::filesystem::path& path, std::uint64_t expected_fingerprint) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(ErrorCode::Io, "cannot open BVH file '" + path.string() + "': " +
                                       (ec ? ec.message() : std::string("not a regular file")));
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(ErrorCode::Io, "cannot open BVH file '" + path.string() + "'");
    f.seekg(0, std::ios::end);
    const std::streamoff size = f.tellg();
    f.seekg(0, std::ios::beg);
    if (!f || size < 0) throw Error(ErrorCode::Io, "cannot read BVH file '" + path.string() + "'");
    const auto file_size = static_cast<std::uint64_t>(size);
    auto read = [&](void* dst, std::size_t n) {
        if (n && !f.read(static_cast<char*>(dst), static_cast<std::streamsize>(n)))
            throw Error(ErrorCode::Io, "cannot read BVH file '" + path.string() + "'");
    };
    // The header first, then each array straight into the BVH: no copy of the file.
    std::uint8_t header[kHeaderSize];
    read(header, static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kHeaderSize)));
    const std::string origin = path.string();
    const Fail fail = [&](const std::string& what) { return Error(ErrorCode::CorruptTree, origin + ": " + what); };
    const Header h = read_header<N>(header, file_size, fail);
    WideBvhN<N> bvh = sized_bvh<N>(h);
    detail::Xxh3 hash;
    hash.update(header, kChecksumOffset);
    read(bvh.nodes.data(), byte_size(bvh.nodes));
    hash.update(bvh.nodes.data(), byte_size(bvh.nodes));
    read(bvh.leaf_objects.data(), byte_size(bvh.leaf_objects));
    hash.update(bvh.leaf_objects.data(), byte_size(bvh.leaf_objects));
    return finish<N>(std::move(bvh), h, hash.digest(), expected_fingerprint, fail);
}

template std::vector<std::uint8_t> serialize_bvh<4>(const WideBvhN<4>&, std::uint64_t);
template std::vector<std::uint8_t> serialize_bvh<8>(const WideBvhN<8>&, std::uint64_t);
template WideBvhN<4> deserialize_bvh<4>(const std::uint8_t*, std::size_t, std::uint64_t, const std::string&);
template WideBvhN<8> deserialize_bvh<8>(const std::uint8_t*, std::size_t, std::uint64_t, const std::string&);
template void save_bvh<4>(const std::filesystem::path&, const WideBvhN<4>&, std::uint64_t);
template void save_bvh<8>(const std::filesystem::path&, const WideBvhN<8>&, std::uint64_t);
template WideBvhN<4> load_bvh<4>(const std::filesystem::path&, std::uint64_t);
template WideBvhN<8> load_bvh<8>(const std::filesystem::path&, std::uint64_t);

}  // namespace kdrt
