// kd-tree files: round trips, and every kind of damage rejected with a
// kdrt::Error rather than a crash (truncation at every length, byte flips,
// forged headers, wrong geometry, wrong magic or version).
#include <catch2/catch.hpp>
#include "tree_forgery.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/kd_tree_io.h>

#include <xxhash.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

constexpr std::uint64_t kFingerprint = 0x0123456789abcdefull;

// A small tree over random boxes, some of them flat, with ropes.
KdTree sample_tree(KdBuilderKind kind, std::size_t n, bool ropes, std::uint32_t seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2.0, 2.0), s(0.0, 0.2);
    KdBuildInput in;
    for (std::size_t i = 0; i < n; ++i) {
        glm::dvec3 c{u(rng), u(rng), u(rng)}, e{s(rng), s(rng), i % 5 == 0 ? 0.0 : s(rng)};
        Aabb b;
        b.lo = c - e;
        b.hi = c + e;
        in.bounds.push_back(b);
    }
    KdBuildConfig config;
    config.builder = kind;
    KdTree tree = build_kd_tree(in, config);
    if (ropes) build_ropes(tree);
    return tree;
}

// The format's checksum (XXH3-64, seed 0, over all bytes but the checksum at
// 116..123), recomputed here from the documentation so that tests can forge files.
void reseal(std::vector<std::uint8_t>& bytes) {
    std::vector<std::uint8_t> covered(bytes.begin(), bytes.begin() + 116);
    covered.insert(covered.end(), bytes.begin() + 124, bytes.end());
    const std::uint64_t h = XXH3_64bits(covered.data(), covered.size());
    for (int i = 0; i < 8; ++i) bytes[116 + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

// Version 1's checksum, FNV-1a 64 over the same bytes: to forge an old file.
void reseal_version1(std::vector<std::uint8_t>& bytes) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        if (i >= 116 && i < 124) continue;
        h ^= bytes[i];
        h *= 0x100000001b3ull;
    }
    for (int i = 0; i < 8; ++i) bytes[116 + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

using test::drop_object;

void put_u32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t v) {
    REQUIRE(at + 4 <= bytes.size());
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_u64(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint64_t v) {
    REQUIRE(at + 8 <= bytes.size());
    for (int i = 0; i < 8; ++i) bytes[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint64_t get_u64(const std::vector<std::uint8_t>& bytes, std::size_t at) {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= std::uint64_t{bytes[at + i]} << (8 * i);
    return v;
}

// The message of the CorruptTree error that loading `bytes` throws ("" if none).
std::string rejection(const std::vector<std::uint8_t>& bytes, std::uint64_t fingerprint = kFingerprint) {
    try {
        deserialize_kd_tree(bytes.data(), bytes.size(), fingerprint, "test.kdtree");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).rfind("test.kdtree: ", 0) == 0);
        return e.what();
    }
    return "";
}

bool mentions(const std::string& message, const std::string& needle) {
    INFO(message);
    return message.find(needle) != std::string::npos;
}

struct TempDir {
    std::filesystem::path path;
    TempDir() {
        path = std::filesystem::temp_directory_path() / ("kdrt_test_io_" + std::to_string(std::random_device{}()));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

}  // namespace

TEST_CASE("kd-tree serialization round-trips exactly", "[kdtree][io]") {
    for (const KdTree& tree : {sample_tree(KdBuilderKind::Sah, 500, true), sample_tree(KdBuilderKind::Sah, 500, false),
                               sample_tree(KdBuilderKind::Median, 300, true), sample_tree(KdBuilderKind::Sah, 0, true),
                               sample_tree(KdBuilderKind::Sah, 1, false)}) {
        const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, kFingerprint);
        const std::size_t expected = 124 + 8 * tree.nodes.size() + 4 * tree.leaf_objects.size() +
                                     + 48 * tree.ropes.size();
        CHECK(bytes.size() == expected);
        const KdTree back = deserialize_kd_tree(bytes.data(), bytes.size(), kFingerprint);
        CHECK(back == tree);
        CHECK(serialize_kd_tree(back, kFingerprint) == bytes);
    }
}

TEST_CASE("kd-tree files follow the documented little-endian layout", "[kdtree][io]") {
    const KdTree tree = sample_tree(KdBuilderKind::Sah, 50, true);
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, kFingerprint);
    CHECK(std::string(bytes.begin(), bytes.begin() + 8) == "KDRTTREE");
    CHECK(std::vector<std::uint8_t>(bytes.begin() + 8, bytes.begin() + 12) == std::vector<std::uint8_t>{3, 0, 0, 0});
    CHECK(get_u64(bytes, 20) == tree.nodes.size());
    CHECK(get_u64(bytes, 28) == 0);  // reserved (version 2's leaf count)
    CHECK(get_u64(bytes, 36) == tree.leaf_objects.size());
    CHECK(get_u64(bytes, 44) == tree.nodes.size());  // ropes by node id
    CHECK(tree.ropes.size() == tree.nodes.size());
    CHECK(get_u64(bytes, 100) == bytes.size() - 124);
    CHECK(get_u64(bytes, 108) == kFingerprint);
    std::vector<std::uint8_t> resealed = bytes;
    reseal(resealed);
    CHECK(resealed == bytes);  // the checksum is the documented one
    // The first node, word0 then word1, right after the header.
    std::uint32_t word1 = 0;
    for (int i = 0; i < 4; ++i) word1 |= std::uint32_t{bytes[128 + i]} << (8 * i);
    CHECK(word1 == tree.nodes[0].word1);
    // A non-empty leaf node: word0 = its first leaf object, word1 = count << 2 | 3;
    // the leaf objects follow the nodes, the ropes (by node id) the leaf objects.
    auto u32_at = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t{bytes[at + i]} << (8 * i);
        return v;
    };
    std::size_t leaf = 0;
    while (!kd_is_leaf(tree.nodes[leaf]) || kd_leaf_count(tree.nodes[leaf]) == 0) ++leaf;
    const std::uint32_t first = u32_at(124 + 8 * leaf), packed = u32_at(124 + 8 * leaf + 4);
    CHECK((packed & 3u) == 3u);
    CHECK(first == kd_leaf_first(tree.nodes[leaf]));
    CHECK((packed >> 2) == kd_leaf_count(tree.nodes[leaf]));
    const std::size_t objects_at = 124 + 8 * tree.nodes.size();
    CHECK(u32_at(objects_at + 4 * first) == tree.leaf_objects[first]);
    const std::size_t ropes_at = objects_at + 4 * tree.leaf_objects.size();
    CHECK(u32_at(ropes_at + 48 * leaf) == tree.ropes[leaf].rope[0]);
    CHECK(std::bit_cast<float>(u32_at(ropes_at + 48 * leaf + 24)) == tree.ropes[leaf].box_min[0]);
}

TEST_CASE("kd-tree files save and load atomically", "[kdtree][io]") {
    TempDir dir;
    const std::filesystem::path file = dir.path / "scene.kdtree";
    const KdTree a = sample_tree(KdBuilderKind::Sah, 400, true), b = sample_tree(KdBuilderKind::Median, 100, false);
    save_kd_tree(file, a, kFingerprint);
    CHECK(load_kd_tree(file, kFingerprint) == a);
    save_kd_tree(file, b, kFingerprint);  // replaces the old file
    CHECK(load_kd_tree(file, kFingerprint) == b);
    CHECK(std::distance(std::filesystem::directory_iterator(dir.path), {}) == 1);  // no temporary left behind

    try {
        load_kd_tree(dir.path / "missing.kdtree", kFingerprint);
        FAIL("loaded a missing file");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Io);
        CHECK(mentions(e.what(), "missing.kdtree"));
    }
    try {
        load_kd_tree(dir.path, kFingerprint);
        FAIL("loaded a directory");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Io);
    }
    try {
        save_kd_tree(dir.path / "no" / "such" / "dir.kdtree", a, kFingerprint);
        FAIL("saved into a missing directory");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Io);
    }
    {  // a damaged file names itself in the message
        std::ofstream(file, std::ios::binary | std::ios::trunc) << "KDRTTREE garbage";
    }
    try {
        load_kd_tree(file, kFingerprint);
        FAIL("loaded garbage");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(mentions(e.what(), file.string() + ": "));
    }
}

TEST_CASE("kd-tree files truncated at every length are rejected", "[kdtree][io]") {
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(sample_tree(KdBuilderKind::Sah, 150, true), kFingerprint);
    REQUIRE(bytes.size() > 1000);
    std::size_t rejected = 0;
    for (std::size_t len = 0; len < bytes.size(); ++len) {
        // A copy of exactly len bytes, so that a sanitizer sees any read past it.
        const std::vector<std::uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(len));
        if (!rejection(prefix).empty()) ++rejected;
    }
    CHECK(rejected == bytes.size());
    std::vector<std::uint8_t> longer = bytes;
    longer.push_back(0);
    CHECK(mentions(rejection(longer), "payload bytes"));
}

TEST_CASE("kd-tree files with a flipped byte are rejected", "[kdtree][io]") {
    const KdTree tree = sample_tree(KdBuilderKind::Sah, 150, true);
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, kFingerprint);
    std::mt19937 rng(99);
    std::size_t rejected = 0;
    for (int i = 0; i < 2000; ++i) {
        std::vector<std::uint8_t> damaged = bytes;
        const std::size_t at = rng() % damaged.size();
        damaged[at] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        try {
            const KdTree t = deserialize_kd_tree(damaged.data(), damaged.size(), kFingerprint);
            CHECK_NOTHROW(check_kd_tree(t));  // a byte no check covers must still leave a sound tree
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::CorruptTree);
            ++rejected;
        }
    }
    CHECK(rejected == 2000);  // the checksum covers every byte of the file
}

TEST_CASE("kd-tree files with the wrong geometry, magic or version are refused", "[kdtree][io]") {
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(sample_tree(KdBuilderKind::Sah, 100, true), kFingerprint);
    CHECK(rejection(bytes).empty());
    CHECK(mentions(rejection(bytes, kFingerprint + 1), "built for different geometry"));

    std::vector<std::uint8_t> b = bytes;
    b[0] = 'X';
    CHECK(mentions(rejection(b), "bad magic"));
    CHECK(mentions(rejection(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 5)), "truncated"));
    CHECK(mentions(rejection({}), "empty file"));

    b = bytes;
    put_u32(b, 8, 4);
    reseal(b);
    CHECK(mentions(rejection(b), "version 4 is newer than this build reads (3)"));
    // A version-2 file (leaf records, ropes per leaf) is refused as such, not misread.
    put_u32(b, 8, 2);
    reseal(b);
    CHECK(mentions(rejection(b), "version 2 is no longer read"));
    put_u32(b, 8, 0);
    reseal(b);
    CHECK(mentions(rejection(b), "unknown kd-tree file format version 0"));
    // A version-1 file (FNV-1a checksum) is refused as such, not misread.
    put_u32(b, 8, 1);
    reseal_version1(b);
    CHECK(mentions(rejection(b), "version 1 is no longer read"));
}

TEST_CASE("kd-tree files with forged headers are rejected without overflow", "[kdtree][io]") {
    const KdTree tree = sample_tree(KdBuilderKind::Sah, 100, true);
    const std::vector<std::uint8_t> bytes = serialize_kd_tree(tree, kFingerprint);
    auto forged = [&](std::size_t at, std::uint64_t value) {
        std::vector<std::uint8_t> b = bytes;
        put_u64(b, at, value);
        reseal(b);
        return rejection(b);
    };
    CHECK(mentions(forged(20, 0), "node count 0"));
    CHECK(mentions(forged(20, std::uint64_t{1} << 62), "node count"));
    CHECK(mentions(forged(36, ~std::uint64_t{0} / 4 + 1), "overflow"));  // 4 * count wraps to 0
    CHECK(mentions(forged(44, 3), "rope count"));
    CHECK(mentions(forged(100, 0), "payload size"));
    CHECK(mentions(forged(28, 1), "reserved"));
    CHECK(mentions(forged(44, tree.nodes.size() - 1), "rope count"));  // version 2's ropes per leaf
    CHECK(mentions(forged(36, tree.leaf_objects.size() + 1), "payload size"));
    CHECK(!forged(52, std::bit_cast<std::uint64_t>(std::nan(""))).empty());  // bounds: caught by check_kd_tree

    std::vector<std::uint8_t> b = bytes;
    put_u32(b, 16, 1000);  // max_depth
    reseal(b);
    CHECK(mentions(rejection(b), "max_depth"));

    // A well-formed file describing a broken tree: check_kd_tree's word, with the origin.
    b = bytes;
    put_u32(b, 128, (1u << 2) | static_cast<std::uint32_t>(kd_axis(tree.nodes[0])));  // root's above child := 1
    reseal(b);
    CHECK(mentions(rejection(b), "test.kdtree: kd-tree node 0: above child 1"));
}

TEST_CASE("kd-tree coverage: a tree that drops an object is refused", "[kdtree][io]") {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-2.0, 2.0), half(0.0, 0.2);
    std::vector<Aabb> bounds;
    for (int i = 0; i < 300; ++i) {
        const glm::dvec3 c{u(rng), u(rng), u(rng)}, h{half(rng), half(rng), half(rng)};
        bounds.push_back({c - h, c + h});
    }
    bounds.push_back({});  // an object with empty bounds is in no leaf, rightly
    for (KdBuilderKind kind : {KdBuilderKind::Sah, KdBuilderKind::Median}) {
        KdBuildConfig config;
        config.builder = kind;
        const KdTree tree = build_kd_tree({bounds, nullptr}, config);
        CHECK_NOTHROW(check_kd_tree_covers(tree, bounds));
        for (std::uint32_t id : {0u, 150u, 299u}) {
            KdTree forged = tree;
            drop_object(forged, id);
            CHECK_NOTHROW(check_kd_tree(forged));  // sound in itself...
            // ...and through a file with a valid checksum, still loadable on its own...
            const std::vector<std::uint8_t> bytes = serialize_kd_tree(forged, kFingerprint);
            CHECK(deserialize_kd_tree(bytes.data(), bytes.size(), kFingerprint) == forged);
            // ...but the coverage check names the missing object.
            try {
                check_kd_tree_covers(forged, bounds);
                FAIL("a tree without object " << id << " passed");
            } catch (const Error& e) {
                CHECK(e.code() == ErrorCode::CorruptTree);
                CHECK(mentions(e.what(), "object " + std::to_string(id)));
            }
        }
        // An object outside the tree's box needs no leaf.
        std::vector<Aabb> outside = bounds;
        outside.push_back({glm::dvec3(10.0), glm::dvec3(11.0)});
        KdTree wider = tree;
        wider.object_count += 1;
        CHECK_NOTHROW(check_kd_tree_covers(wider, outside));
        CHECK_THROWS_AS(check_kd_tree_covers(tree, outside), Error);  // object counts differ
    }
}
