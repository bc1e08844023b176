// Binary kd-tree files.
//
// Format, version 1. Integers are little-endian; floats are their IEEE-754 bit
// patterns (binary32 / binary64) stored as little-endian integers; no padding.
// Everything is written and read byte by byte, whatever the host's byte order.
//
//   offset size  field
//        0    8  magic "KDRTTREE" (ASCII)
//        8    4  u32 format version = 1
//       12    4  u32 object_count       objects the tree was built over
//       16    4  u32 max_depth          depth limit it was built with, <= 64
//       20    8  u64 node_count         >= 1
//       28    8  u64 leaf_count
//       36    8  u64 leaf_object_count
//       44    8  u64 rope_count         0 (no ropes) or leaf_count
//       52   48  f64 bounds             lo.x lo.y lo.z hi.x hi.y hi.z
//      100    8  u64 payload_size       = 8 node_count + 8 leaf_count
//                                         + 4 leaf_object_count + 48 rope_count
//      108    8  u64 geometry fingerprint (see kd_tree_io.h)
//      116    8  u64 checksum           FNV-1a 64 (offset basis 0xcbf29ce484222325,
//                                         prime 0x100000001b3) over bytes [0, 116)
//                                         then the payload: every byte but itself
//      124       payload, in this order:
//                  nodes         node_count x        (u32 word0, u32 word1)
//                  leaves        leaf_count x        (u32 first, u32 count)
//                  leaf objects  leaf_object_count x u32 object id
//                  ropes         rope_count x        (6 x u32 rope, 3 x f32 box_min, 3 x f32 box_max)
//
// The file is exactly 124 + payload_size bytes. FNV-1a changes its value for
// any single changed byte (each step is a bijection of the state), so a
// flipped byte anywhere is caught. Loading checks, in order: magic, version,
// the counts and sizes against the file's length (overflow-safe), checksum,
// fingerprint, then check_kd_tree on the decoded tree.
#include "common/atomic_file.h"
#include "common/fnv1a.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

namespace kdrt {

namespace {

constexpr char kMagic[8] = {'K', 'D', 'R', 'T', 'T', 'R', 'E', 'E'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kChecksumOffset = 116;
constexpr std::size_t kHeaderSize = 124;

std::uint64_t file_checksum(const std::uint8_t* data, std::size_t size) {
    const std::uint64_t h = detail::fnv1a(detail::kFnv1aOffsetBasis, data, kChecksumOffset);
    return detail::fnv1a(h, data + kHeaderSize, size - kHeaderSize);
}

class ByteWriter {
public:
    explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
    void u32(std::uint32_t v) {
        for (int i = 0; i < 4; ++i) out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }

private:
    std::vector<std::uint8_t>& out_;
};

// Reads little-endian values; the caller has checked the sizes, the bound
// check here only keeps a logic error from reading past the buffer.
class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size, std::size_t pos) : data_(data), size_(size), pos_(pos) {}
    std::uint32_t u32() {
        need(4);
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t{data_[pos_++]} << (8 * i);
        return v;
    }
    std::uint64_t u64() {
        need(8);
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t{data_[pos_++]} << (8 * i);
        return v;
    }
    float f32() { return std::bit_cast<float>(u32()); }
    double f64() { return std::bit_cast<double>(u64()); }

private:
    void need(std::size_t n) const {
        if (size_ - pos_ < n) throw Error(ErrorCode::CorruptTree, "kd-tree file: read past the end");
    }
    const std::uint8_t* data_;
    std::size_t size_, pos_;
};

// acc += count * item_size; false on overflow.
bool add_array_size(std::uint64_t& acc, std::uint64_t count, std::uint64_t item_size) {
    if (count > (UINT64_MAX - acc) / item_size) return false;
    acc += count * item_size;
    return true;
}

std::string hex(std::uint64_t v) {
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

}  // namespace

std::vector<std::uint8_t> serialize_kd_tree(const KdTree& tree, std::uint64_t geometry_fingerprint) {
    const std::uint64_t payload = 8 * std::uint64_t{tree.nodes.size()} + 8 * std::uint64_t{tree.leaves.size()} +
                                  4 * std::uint64_t{tree.leaf_objects.size()} + 48 * std::uint64_t{tree.ropes.size()};
    std::vector<std::uint8_t> out;
    out.reserve(kHeaderSize + payload);
    ByteWriter w(out);
    for (char c : kMagic) out.push_back(static_cast<std::uint8_t>(c));
    w.u32(kVersion);
    w.u32(tree.object_count);
    w.u32(static_cast<std::uint32_t>(tree.max_depth));
    w.u64(tree.nodes.size());
    w.u64(tree.leaves.size());
    w.u64(tree.leaf_objects.size());
    w.u64(tree.ropes.size());
    for (int k = 0; k < 3; ++k) w.f64(tree.bounds.lo[k]);
    for (int k = 0; k < 3; ++k) w.f64(tree.bounds.hi[k]);
    w.u64(payload);
    w.u64(geometry_fingerprint);
    w.u64(0);  // checksum, filled in below
    for (const KdNode& n : tree.nodes) {
        w.u32(n.word0);
        w.u32(n.word1);
    }
    for (const KdLeaf& l : tree.leaves) {
        w.u32(l.first);
        w.u32(l.count);
    }
    for (std::uint32_t id : tree.leaf_objects) w.u32(id);
    for (const KdLeafRopes& r : tree.ropes) {
        for (std::uint32_t rope : r.rope) w.u32(rope);
        for (float v : r.box_min) w.f32(v);
        for (float v : r.box_max) w.f32(v);
    }
    const std::uint64_t checksum = file_checksum(out.data(), out.size());
    for (int i = 0; i < 8; ++i) out[kChecksumOffset + i] = static_cast<std::uint8_t>(checksum >> (8 * i));
    return out;
}

KdTree deserialize_kd_tree(const std::uint8_t* data, std::size_t size, std::uint64_t expected_fingerprint,
                           const std::string& origin) {
    auto fail = [&](const std::string& what) -> Error { return Error(ErrorCode::CorruptTree, origin + ": " + what); };

    if (size == 0) throw fail("empty file, not a kd-tree");
    if (std::memcmp(data, kMagic, std::min<std::size_t>(size, 8)) != 0)
        throw fail("not a kdrt kd-tree file (bad magic)");
    if (size < 12) throw fail("truncated kd-tree file: " + std::to_string(size) + " bytes, no format version");
    const std::uint32_t version = ByteReader(data, size, 8).u32();
    if (version > kVersion)
        throw fail("kd-tree file format version " + std::to_string(version) + " is newer than this build reads (" +
                   std::to_string(kVersion) + "); rebuild the tree");
    if (version != kVersion) throw fail("unknown kd-tree file format version " + std::to_string(version));
    if (size < kHeaderSize)
        throw fail("truncated kd-tree file: " + std::to_string(size) + " bytes, shorter than the " +
                   std::to_string(kHeaderSize) + "-byte header");

    ByteReader r(data, size, 12);
    const std::uint32_t object_count = r.u32();
    const std::uint32_t max_depth = r.u32();
    const std::uint64_t node_count = r.u64(), leaf_count = r.u64(), leaf_object_count = r.u64(), rope_count = r.u64();
    Aabb bounds;
    for (int k = 0; k < 3; ++k) bounds.lo[k] = r.f64();
    for (int k = 0; k < 3; ++k) bounds.hi[k] = r.f64();
    const std::uint64_t payload_size = r.u64();
    const std::uint64_t fingerprint = r.u64();
    const std::uint64_t checksum = r.u64();

    if (max_depth > KDRT_MAX_TREE_DEPTH) throw fail("max_depth " + std::to_string(max_depth) + " exceeds 64");
    if (node_count == 0 || node_count > std::uint64_t{KDRT_MAX_NODE_INDEX} + 1)
        throw fail("node count " + std::to_string(node_count) + " is out of range");
    if (rope_count != 0 && rope_count != leaf_count)
        throw fail("rope count " + std::to_string(rope_count) + " is neither 0 nor the leaf count " +
                   std::to_string(leaf_count));
    std::uint64_t expected_payload = 0;
    if (!add_array_size(expected_payload, node_count, 8) || !add_array_size(expected_payload, leaf_count, 8) ||
        !add_array_size(expected_payload, leaf_object_count, 4) || !add_array_size(expected_payload, rope_count, 48))
        throw fail("array sizes overflow");
    if (payload_size != expected_payload)
        throw fail("payload size " + std::to_string(payload_size) + " does not match the counts (" +
                   std::to_string(expected_payload) + ")");
    if (payload_size != size - kHeaderSize)
        throw fail("file has " + std::to_string(size - kHeaderSize) + " payload bytes, the header announces " +
                   std::to_string(payload_size) + (size - kHeaderSize < payload_size ? " (truncated)" : ""));
    const std::uint64_t actual = file_checksum(data, size);
    if (checksum != actual) throw fail("checksum mismatch (stored " + hex(checksum) + ", computed " + hex(actual) + ")");
    if (fingerprint != expected_fingerprint)
        throw fail("the kd-tree was built for different geometry (fingerprint " + hex(fingerprint) + ", expected " +
                   hex(expected_fingerprint) + "); rebuild it");

    KdTree tree;
    tree.object_count = object_count;
    tree.max_depth = static_cast<int>(max_depth);
    tree.bounds = bounds;
    tree.nodes.resize(node_count);
    tree.leaves.resize(leaf_count);
    tree.leaf_objects.resize(leaf_object_count);
    tree.ropes.resize(rope_count);
    for (KdNode& n : tree.nodes) {
        n.word0 = r.u32();
        n.word1 = r.u32();
    }
    for (KdLeaf& l : tree.leaves) {
        l.first = r.u32();
        l.count = r.u32();
    }
    for (std::uint32_t& id : tree.leaf_objects) id = r.u32();
    for (KdLeafRopes& rp : tree.ropes) {
        for (std::uint32_t& rope : rp.rope) rope = r.u32();
        for (float& v : rp.box_min) v = r.f32();
        for (float& v : rp.box_max) v = r.f32();
    }
    try {
        check_kd_tree(tree);
    } catch (const Error& e) {
        throw fail(e.what());
    }
    return tree;
}

void save_kd_tree(const std::filesystem::path& path, const KdTree& tree, std::uint64_t geometry_fingerprint) {
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, geometry_fingerprint);
    // Write beside the target and rename over it, so readers never see half a file.
    detail::write_file_atomically(path, bytes);
}

KdTree load_kd_tree(const std::filesystem::path& path, std::uint64_t expected_fingerprint) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(ErrorCode::Io, "cannot open kd-tree file '" + path.string() + "': " +
                                       (ec ? ec.message() : std::string("not a regular file")));
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(ErrorCode::Io, "cannot open kd-tree file '" + path.string() + "'");
    f.seekg(0, std::ios::end);
    const std::streamoff size = f.tellg();
    f.seekg(0, std::ios::beg);
    if (!f || size < 0) throw Error(ErrorCode::Io, "cannot read kd-tree file '" + path.string() + "'");
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
    f.read(reinterpret_cast<char*>(bytes.data()), size);
    if (!f) throw Error(ErrorCode::Io, "cannot read kd-tree file '" + path.string() + "'");
    return deserialize_kd_tree(bytes.data(), bytes.size(), expected_fingerprint, path.string());
}

}  // namespace kdrt
