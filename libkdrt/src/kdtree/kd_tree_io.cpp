// Binary kd-tree files.
//
// Format, version 3. Integers are little-endian; floats are their IEEE-754 bit
// patterns (binary32 / binary64) stored as little-endian integers; no padding.
// The header is written and read field by field; the arrays, all made of
// 32-bit words, are copied in bulk (one memcpy or read per array, each word
// byte-swapped on a big-endian host), so loading runs at memory speed.
//
//   offset size  field
//        0    8  magic "KDRTTREE" (ASCII)
//        8    4  u32 format version = 3
//       12    4  u32 object_count       objects the tree was built over
//       16    4  u32 max_depth          depth limit it was built with, <= 64
//       20    8  u64 node_count         >= 1
//       28    8  u64 reserved = 0      (version 2: leaf_count)
//       36    8  u64 leaf_object_count
//       44    8  u64 rope_count         0 (no ropes) or node_count
//       52   48  f64 bounds             lo.x lo.y lo.z hi.x hi.y hi.z
//      100    8  u64 payload_size       = 8 node_count + 4 leaf_object_count
//                                         + 48 rope_count
//      108    8  u64 geometry fingerprint (see kd_tree_io.h)
//      116    8  u64 checksum           XXH3-64 (seed 0) of bytes [0, 116)
//                                         followed by the payload: every byte but itself
//      124       payload, in this order:
//                  nodes         node_count x        (u32 word0, u32 word1; a leaf's word0 is
//                                                     its first leaf object, see kdrt/layout.h)
//                  leaf objects  leaf_object_count x u32 object id
//                  ropes         rope_count x        (6 x u32 rope, 3 x f32 box_min, 3 x f32 box_max),
//                                                     indexed by node id
//
// The file is exactly 124 + payload_size bytes. Version 2 (leaf records
// {first, count} indexed by the leaf node, ropes per leaf) and version 1 (as 2,
// with a byte-wise FNV-1a checksum) are refused: rebuild the tree. XXH3 is not
// a cryptographic hash, so the checksum catches damage, not forgery: a forged
// file with a recomputed checksum still has to pass check_kd_tree (every index
// in range, depth-first, no cycles) and, against its scene, the render's
// coverage check (check_kd_tree_covers). Loading checks, in order: magic,
// version, the counts and sizes against the file's length (overflow-safe),
// checksum, fingerprint, then check_kd_tree on the decoded tree.
#include "common/atomic_file.h"
#include "common/tree_file_bytes.h"
#include "common/tree_file_kind.h"
#include "common/xxh3.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <sstream>
#include <system_error>

namespace kdrt {

namespace {

constexpr char kMagic[8] = {'K', 'D', 'R', 'T', 'T', 'R', 'E', 'E'};
constexpr std::uint32_t kVersion = 3;
constexpr std::size_t kChecksumOffset = 116;
constexpr std::size_t kHeaderSize = 124;

// The payload arrays are copied as 32-bit words.
static_assert(sizeof(KdNode) % 4 == 0 && sizeof(KdLeafRopes) % 4 == 0 &&
              sizeof(float) == 4);
using detail::add_array_size;
using detail::byte_size;
using detail::hex;
using detail::swap_words_if_big_endian;
using Fail = detail::TreeFileFail;

template <class T>
void append_words(std::vector<std::uint8_t>& out, const std::vector<T>& v) {
    const std::size_t at = out.size();
    out.resize(at + byte_size(v));
    if (v.empty()) return;
    std::memcpy(out.data() + at, v.data(), byte_size(v));
    swap_words_if_big_endian(out.data() + at, byte_size(v));
}

class ByteWriter {
public:
    explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
    void u32(std::uint32_t v) { detail::put_le(out_, v, 4); }
    void u64(std::uint64_t v) { detail::put_le(out_, v, 8); }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }

private:
    std::vector<std::uint8_t>& out_;
};

// Reads little-endian header fields; the caller has checked the sizes, the
// bound check here only keeps a logic error from reading past the buffer.
class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size, std::size_t pos) : data_(data), size_(size), pos_(pos) {}
    std::uint32_t u32() {
        need(4);
        pos_ += 4;
        return static_cast<std::uint32_t>(detail::get_le(data_ + pos_ - 4, 4));
    }
    std::uint64_t u64() {
        need(8);
        pos_ += 8;
        return detail::get_le(data_ + pos_ - 8, 8);
    }
    double f64() { return std::bit_cast<double>(u64()); }

private:
    void need(std::size_t n) const {
        if (size_ - pos_ < n) throw Error(ErrorCode::CorruptTree, "kd-tree file: read past the end");
    }
    const std::uint8_t* data_;
    std::size_t size_, pos_;
};

struct Header {
    std::uint32_t object_count = 0, max_depth = 0;
    std::uint64_t node_count = 0, reserved = 0, leaf_object_count = 0, rope_count = 0;
    Aabb bounds;
    std::uint64_t fingerprint = 0, checksum = 0;
};

// Decodes and checks the header of a file of `file_size` bytes, whose first
// min(file_size, kHeaderSize) bytes are at `data`: magic, version, and the
// counts against the file's length.
Header read_header(const std::uint8_t* data, std::uint64_t file_size, const Fail& fail) {
    const std::size_t have = static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kHeaderSize));
    if (file_size == 0) throw fail("empty file, not a kd-tree");
    if (detail::tree_file_kind(data, have) == detail::TreeFileKind::WideBvh)
        throw fail("is a BVH file, not a kd-tree file: load it as a BVH (Accel::Bvh, kdrt-render --accel bvh), "
                   "or build a kd-tree");
    if (std::memcmp(data, kMagic, std::min<std::size_t>(have, 8)) != 0)
        throw fail("not a kdrt kd-tree file (bad magic)");
    if (have < 12) throw fail("truncated kd-tree file: " + std::to_string(file_size) + " bytes, no format version");
    const std::uint32_t version = ByteReader(data, have, 8).u32();
    if (version > kVersion)
        throw fail("kd-tree file format version " + std::to_string(version) + " is newer than this build reads (" +
                   std::to_string(kVersion) + "); rebuild the tree");
    if (version == 1 || version == 2)
        throw fail("kd-tree file format version " + std::to_string(version) + " is no longer read (this build reads " + std::to_string(kVersion) +
                   "); rebuild the tree");
    if (version != kVersion) throw fail("unknown kd-tree file format version " + std::to_string(version));
    if (have < kHeaderSize)
        throw fail("truncated kd-tree file: " + std::to_string(file_size) + " bytes, shorter than the " +
                   std::to_string(kHeaderSize) + "-byte header");

    ByteReader r(data, have, 12);
    Header h;
    h.object_count = r.u32();
    h.max_depth = r.u32();
    h.node_count = r.u64();
    h.reserved = r.u64();
    h.leaf_object_count = r.u64();
    h.rope_count = r.u64();
    for (int k = 0; k < 3; ++k) h.bounds.lo[k] = r.f64();
    for (int k = 0; k < 3; ++k) h.bounds.hi[k] = r.f64();
    const std::uint64_t payload_size = r.u64();
    h.fingerprint = r.u64();
    h.checksum = r.u64();

    if (h.max_depth > KDRT_MAX_TREE_DEPTH) throw fail("max_depth " + std::to_string(h.max_depth) + " exceeds 64");
    if (h.node_count == 0 || h.node_count > std::uint64_t{KDRT_MAX_NODE_INDEX} + 1)
        throw fail("node count " + std::to_string(h.node_count) + " is out of range");
    if (h.reserved != 0) throw fail("reserved header field (offset 28) is " + std::to_string(h.reserved) + ", not 0");
    if (h.rope_count != 0 && h.rope_count != h.node_count)
        throw fail("rope count " + std::to_string(h.rope_count) + " is neither 0 nor the node count " +
                   std::to_string(h.node_count));
    std::uint64_t expected_payload = 0;
    if (!add_array_size(expected_payload, h.node_count, sizeof(KdNode)) ||
        !add_array_size(expected_payload, h.leaf_object_count, 4) ||
        !add_array_size(expected_payload, h.rope_count, sizeof(KdLeafRopes)))
        throw fail("array sizes overflow");
    if (payload_size != expected_payload)
        throw fail("payload size " + std::to_string(payload_size) + " does not match the counts (" +
                   std::to_string(expected_payload) + ")");
    if (payload_size != file_size - kHeaderSize)
        throw fail("file has " + std::to_string(file_size - kHeaderSize) + " payload bytes, the header announces " +
                   std::to_string(payload_size) + (file_size - kHeaderSize < payload_size ? " (truncated)" : ""));
    return h;
}

// A tree with the header's scalars and its arrays sized, ready to be filled.
KdTree sized_tree(const Header& h) {
    KdTree tree;
    tree.object_count = h.object_count;
    tree.max_depth = static_cast<int>(h.max_depth);
    tree.bounds = h.bounds;
    tree.nodes.resize(h.node_count);
    tree.leaf_objects.resize(h.leaf_object_count);
    tree.ropes.resize(h.rope_count);
    return tree;
}

// Checks the checksum (of the arrays still in file byte order), the
// fingerprint and the structure, and brings the arrays into host order.
KdTree finish(KdTree tree, const Header& h, std::uint64_t actual_checksum, std::uint64_t expected_fingerprint,
              const Fail& fail) {
    if (h.checksum != actual_checksum)
        throw fail("checksum mismatch (stored " + hex(h.checksum) + ", computed " + hex(actual_checksum) + ")");
    if (h.fingerprint != expected_fingerprint)
        throw fail("the kd-tree was built for different geometry (fingerprint " + hex(h.fingerprint) +
                   ", expected " + hex(expected_fingerprint) + "); rebuild it");
    swap_words_if_big_endian(tree.nodes);
    swap_words_if_big_endian(tree.leaf_objects);
    swap_words_if_big_endian(tree.ropes);
    try {
        check_kd_tree(tree);
    } catch (const Error& e) {
        throw fail(e.what());
    }
    return tree;
}

}  // namespace

std::vector<std::uint8_t> serialize_kd_tree(const KdTree& tree, std::uint64_t geometry_fingerprint) {
    const std::uint64_t payload = byte_size(tree.nodes) + byte_size(tree.leaf_objects) +
                                  byte_size(tree.ropes);
    std::vector<std::uint8_t> out;
    out.reserve(kHeaderSize + payload);
    ByteWriter w(out);
    for (char c : kMagic) out.push_back(static_cast<std::uint8_t>(c));
    w.u32(kVersion);
    w.u32(tree.object_count);
    w.u32(static_cast<std::uint32_t>(tree.max_depth));
    w.u64(tree.nodes.size());
    w.u64(0);  // reserved
    w.u64(tree.leaf_objects.size());
    w.u64(tree.ropes.size());
    for (int k = 0; k < 3; ++k) w.f64(tree.bounds.lo[k]);
    for (int k = 0; k < 3; ++k) w.f64(tree.bounds.hi[k]);
    w.u64(payload);
    w.u64(geometry_fingerprint);
    w.u64(0);  // checksum, filled in below
    append_words(out, tree.nodes);
    append_words(out, tree.leaf_objects);
    append_words(out, tree.ropes);
    detail::Xxh3 hash;
    hash.update(out.data(), kChecksumOffset);
    hash.update(out.data() + kHeaderSize, out.size() - kHeaderSize);
    const std::uint64_t checksum = hash.digest();
    for (int i = 0; i < 8; ++i) out[kChecksumOffset + i] = static_cast<std::uint8_t>(checksum >> (8 * i));
    return out;
}

KdTree deserialize_kd_tree(const std::uint8_t* data, std::size_t size, std::uint64_t expected_fingerprint,
                           const std::string& origin) {
    const Fail fail = [&](const std::string& what) { return Error(ErrorCode::CorruptTree, origin + ": " + what); };
    const Header h = read_header(data, size, fail);
    KdTree tree = sized_tree(h);
    detail::Xxh3 hash;
    hash.update(data, kChecksumOffset);
    std::size_t at = kHeaderSize;
    auto take = [&](auto& v) {
        if (v.empty()) return;
        std::memcpy(v.data(), data + at, byte_size(v));
        hash.update(data + at, byte_size(v));
        at += byte_size(v);
    };
    take(tree.nodes);
    take(tree.leaf_objects);
    take(tree.ropes);
    return finish(std::move(tree), h, hash.digest(), expected_fingerprint, fail);
}

void save_kd_tree(const std::filesystem::path& path, const KdTree& tree, std::uint64_t geometry_fingerprint) {
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, geometry_fingerprint);
    // Write beside the target and rename over it, so readers never see half a file.
    detail::write_file_atomically(path, bytes);
}

KdTree load_kd_tree(const std::filesystem::path& path, std::uint64_t expected_fingerprint) {
    // O_NONBLOCK: a FIFO (in a tree cache, say) opens at once and is refused
    // by the type check on the descriptor instead of blocking for a writer.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw Error(ErrorCode::Io, "cannot open kd-tree file '" + path.string() + "': " + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
        throw Error(ErrorCode::Io, "cannot open kd-tree file '" + path.string() + "': not a regular file");
    const auto file_size = static_cast<std::uint64_t>(st.st_size);
    auto read = [&](void* dst, std::size_t n) {
        auto* out = static_cast<char*>(dst);
        while (n > 0) {
            const ssize_t got = ::read(fd, out, n);
            if (got < 0 && errno == EINTR) continue;
            if (got <= 0) throw Error(ErrorCode::Io, "cannot read kd-tree file '" + path.string() + "'");
            out += got;
            n -= static_cast<std::size_t>(got);
        }
    };

    // The header first, then each array straight into the tree: no copy of the file.
    std::uint8_t header[kHeaderSize];
    read(header, static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kHeaderSize)));
    const std::string origin = path.string();
    const Fail fail = [&](const std::string& what) { return Error(ErrorCode::CorruptTree, origin + ": " + what); };
    const Header h = read_header(header, file_size, fail);
    KdTree tree = sized_tree(h);
    detail::Xxh3 hash;
    hash.update(header, kChecksumOffset);
    auto take = [&](auto& v) {
        read(v.data(), byte_size(v));
        hash.update(v.data(), byte_size(v));
    };
    take(tree.nodes);
    take(tree.leaf_objects);
    take(tree.ropes);
    return finish(std::move(tree), h, hash.digest(), expected_fingerprint, fail);
}

}  // namespace kdrt
