// BVH files: round trips, the documented layout, and every kind of damage
// refused with a kdrt::Error rather than a crash (truncation at every length,
// byte flips, forged headers and structures, wrong geometry, width, version
// or kind of tree).
#include "temp_dir.h"

#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"
#include "bvh/bvh_io.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/kd_tree_io.h>

#include <catch2/catch.hpp>

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

constexpr std::uint64_t kFingerprint = 0xfedcba9876543210ull;

std::vector<Aabb> random_boxes(std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2.0, 2.0), s(0.0, 0.2);
    std::vector<Aabb> boxes;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 c{u(rng), u(rng), u(rng)}, e{s(rng), s(rng), i % 5 == 0 ? 0.0 : s(rng)};
        boxes.push_back({c - e, c + e});
    }
    return boxes;
}

template <int N = kWideBvhWidth>
WideBvhN<N> sample_bvh(std::size_t n, std::uint32_t seed = 7) {
    const std::vector<Aabb> boxes = random_boxes(n, seed);
    BvhBuildConfig config;
    config.max_leaf_size = 3;
    return build_wide_bvh<N>(BvhBuildInput{boxes, static_cast<std::uint32_t>(n / 4)}, config);
}

// The format's checksum (XXH3-64 of every byte but 112..119), recomputed from
// the documentation so that tests can forge files.
void reseal(std::vector<std::uint8_t>& bytes) {
    std::vector<std::uint8_t> covered(bytes.begin(), bytes.begin() + 112);
    covered.insert(covered.end(), bytes.begin() + 120, bytes.end());
    const std::uint64_t h = XXH3_64bits(covered.data(), covered.size());
    for (int i = 0; i < 8; ++i) bytes[112 + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

std::uint64_t get(const std::vector<std::uint8_t>& bytes, std::size_t at, int size) {
    std::uint64_t v = 0;
    for (int i = 0; i < size; ++i) v |= std::uint64_t{bytes[at + i]} << (8 * i);
    return v;
}
void put(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint64_t v, int size) {
    for (int i = 0; i < size; ++i) bytes[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// The message of the CorruptTree error that loading `bytes` throws ("" if none).
template <int N = kWideBvhWidth>
std::string rejection(const std::vector<std::uint8_t>& bytes, std::uint64_t fingerprint = kFingerprint) {
    try {
        deserialize_bvh<N>(bytes.data(), bytes.size(), fingerprint, "test.bvh");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).rfind("test.bvh: ", 0) == 0);
        return e.what();
    }
    return "";
}

bool mentions(const std::string& message, const std::string& needle) {
    INFO("message: " << message << "; expected: " << needle);
    return message.find(needle) != std::string::npos;
}

}  // namespace

TEST_CASE("bvh files round-trip exactly", "[bvh][io]") {
    for (const WideBvh& bvh : {sample_bvh(500), sample_bvh(1), sample_bvh(0), sample_bvh(3000, 9)}) {
        const std::vector<std::uint8_t> bytes = serialize_bvh(bvh, kFingerprint);
        CHECK(bytes.size() == 120 + 256 * bvh.nodes.size() + 4 * bvh.leaf_objects.size());
        const WideBvh back = deserialize_bvh(bytes.data(), bytes.size(), kFingerprint);
        CHECK(back == bvh);
        CHECK(serialize_bvh(back, kFingerprint) == bytes);
    }
    const WideBvhN<4> four = sample_bvh<4>(700);
    const std::vector<std::uint8_t> bytes = serialize_bvh(four, kFingerprint);
    CHECK(bytes.size() == 120 + 128 * four.nodes.size() + 4 * four.leaf_objects.size());
    CHECK(deserialize_bvh<4>(bytes.data(), bytes.size(), kFingerprint) == four);
}

TEST_CASE("bvh files follow the documented little-endian layout", "[bvh][io]") {
    const WideBvh bvh = sample_bvh(200);
    const std::vector<std::uint8_t> bytes = serialize_bvh(bvh, kFingerprint);
    CHECK(std::string(bytes.begin(), bytes.begin() + 8) == "KDRTWBVH");
    CHECK(get(bytes, 8, 4) == 1);   // version
    CHECK(get(bytes, 12, 4) == 8);  // width
    CHECK(get(bytes, 16, 4) == bvh.object_count);
    CHECK(get(bytes, 20, 4) == 0);
    CHECK(get(bytes, 24, 8) == bvh.nodes.size());
    CHECK(get(bytes, 32, 8) == bvh.leaf_objects.size());
    CHECK(std::bit_cast<double>(get(bytes, 40, 8)) == bvh.bounds.lo.x);
    CHECK(std::bit_cast<double>(get(bytes, 80, 8)) == bvh.bounds.hi.z);
    CHECK(std::bit_cast<double>(get(bytes, 88, 8)) == bvh.build_sah_cost);
    CHECK(get(bytes, 96, 8) == bytes.size() - 120);
    CHECK(get(bytes, 104, 8) == kFingerprint);
    std::vector<std::uint8_t> resealed = bytes;
    reseal(resealed);
    CHECK(resealed == bytes);
    // Node 1: its lower x bounds (8 floats), ..., its children (8 u32), its counts (8 u32).
    const std::size_t node1 = 120 + 256;
    CHECK(std::bit_cast<float>(static_cast<std::uint32_t>(get(bytes, node1 + 4 * 3, 4))) == bvh.nodes[1].box[0][0][3]);
    CHECK(std::bit_cast<float>(static_cast<std::uint32_t>(get(bytes, node1 + 96 + 4 * 8 + 4, 4))) ==
          bvh.nodes[1].box[1][1][1]);
    CHECK(get(bytes, node1 + 192, 4) == bvh.nodes[1].child[0]);
    CHECK(get(bytes, node1 + 224 + 4 * 7, 4) == bvh.nodes[1].count[7]);
    const std::size_t objects = 120 + 256 * bvh.nodes.size();
    CHECK(get(bytes, objects + 4 * 5, 4) == bvh.leaf_objects[5]);
}

TEST_CASE("bvh files save and load atomically, and name themselves in errors", "[bvh][io]") {
    test::TempDir dir("kdrt_test_bvh_io");
    const std::filesystem::path file = dir.path / "scene.bvh";
    const WideBvh a = sample_bvh(400), b = sample_bvh(100, 3);
    save_bvh(file, a, kFingerprint);
    CHECK(load_bvh(file, kFingerprint) == a);
    save_bvh(file, b, kFingerprint);
    CHECK(load_bvh(file, kFingerprint) == b);
    CHECK(std::distance(std::filesystem::directory_iterator(dir.path), {}) == 1);
    try {
        load_bvh(dir.path / "missing.bvh", kFingerprint);
        FAIL("loaded a missing file");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Io);
        CHECK(mentions(e.what(), "missing.bvh"));
    }
    CHECK_THROWS_AS(save_bvh(dir.path / "no" / "dir.bvh", a, kFingerprint), Error);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << "KDRTWBVH garbage";
    try {
        load_bvh(file, kFingerprint);
        FAIL("loaded garbage");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(mentions(e.what(), file.string() + ": "));
    }
    // The file's width must be the one asked for.
    save_bvh(file, sample_bvh<4>(50), kFingerprint);
    CHECK_THROWS_AS(load_bvh<8>(file, kFingerprint), Error);
    CHECK_NOTHROW(load_bvh<4>(file, kFingerprint));
}

TEST_CASE("bvh files truncated at every length are refused", "[bvh][io]") {
    const std::vector<std::uint8_t> bytes = serialize_bvh(sample_bvh(60), kFingerprint);
    REQUIRE(bytes.size() > 1000);
    std::size_t rejected = 0;
    for (std::size_t len = 0; len < bytes.size(); ++len) {
        const std::vector<std::uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(len));
        rejected += !rejection(prefix).empty();
    }
    CHECK(rejected == bytes.size());
    std::vector<std::uint8_t> longer = bytes;
    longer.push_back(0);
    CHECK(mentions(rejection(longer), "payload bytes"));
}

TEST_CASE("bvh files with a flipped byte are refused", "[bvh][io]") {
    const std::vector<std::uint8_t> bytes = serialize_bvh(sample_bvh(150), kFingerprint);
    std::mt19937 rng(99);
    std::size_t rejected = 0;
    for (int i = 0; i < 2000; ++i) {
        std::vector<std::uint8_t> damaged = bytes;
        damaged[rng() % damaged.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        rejected += !rejection(damaged).empty();
    }
    CHECK(rejected == 2000);  // the checksum covers every byte
}

TEST_CASE("bvh files of another geometry, version, width or kind of tree are refused, saying so", "[bvh][io]") {
    const std::vector<std::uint8_t> bytes = serialize_bvh(sample_bvh(100), kFingerprint);
    CHECK(rejection(bytes).empty());
    CHECK(mentions(rejection(bytes, kFingerprint + 1), "built for different geometry"));
    std::vector<std::uint8_t> b = bytes;
    b[0] = 'X';
    CHECK(mentions(rejection(b), "bad magic"));
    b = bytes;
    put(b, 8, 2, 4);
    reseal(b);
    CHECK(mentions(rejection(b), "newer than this build reads"));
    b = bytes;
    put(b, 8, 0, 4);
    reseal(b);
    CHECK(mentions(rejection(b), "unknown BVH file format version 0"));
    CHECK(mentions(rejection<4>(bytes), "width 8"));
    CHECK(mentions(rejection(std::vector<std::uint8_t>{}), "empty file"));

    // A kd-tree file where a BVH is expected, and the other way round.
    KdBuildInput in;
    in.bounds = random_boxes(50, 2);
    const std::vector<std::uint8_t> kd = serialize_kd_tree(build_kd_tree(in, {}), kFingerprint);
    CHECK(mentions(rejection(kd), "is a kd-tree file, not a BVH file"));
    try {
        deserialize_kd_tree(bytes.data(), bytes.size(), kFingerprint, "test.kdtree");
        FAIL("a BVH file loaded as a kd-tree");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(mentions(e.what(), "is a BVH file, not a kd-tree file"));
    }
}

TEST_CASE("bvh files with forged headers and structures are refused", "[bvh][io]") {
    const WideBvh bvh = sample_bvh(300);
    const std::vector<std::uint8_t> bytes = serialize_bvh(bvh, kFingerprint);
    auto forged = [&](auto&& change) {
        std::vector<std::uint8_t> b = bytes;
        change(b);
        reseal(b);
        return rejection(b);
    };
    CHECK(mentions(forged([](auto& b) { put(b, 20, 1, 4); }), "reserved"));
    CHECK(mentions(forged([](auto& b) { put(b, 24, 0, 8); }), "node count 0"));
    CHECK(mentions(forged([](auto& b) { put(b, 24, 1ull << 40, 8); }), "node count"));
    CHECK(mentions(forged([&](auto& b) { put(b, 32, bvh.object_count + 1ull, 8); }), "exceeds the object count"));
    CHECK(mentions(forged([](auto& b) { put(b, 88, std::bit_cast<std::uint64_t>(std::nan("")), 8); }),
                   "build SAH cost"));
    CHECK(mentions(forged([](auto& b) { put(b, 96, get(b, 96, 8) + 4, 8); }), "does not match the counts"));
    CHECK(mentions(forged([&](auto& b) { put(b, 32, bvh.leaf_objects.size() - 1, 8); }), "does not match the counts"));
    // Structures behind a valid checksum: check_bvh's messages, with the file's name.
    const std::size_t node1 = 120 + 256;
    CHECK(mentions(forged([&](auto& b) { put(b, node1 + 192, bvh.nodes.size() + 5, 4); }), "BVH node 1"));
    CHECK(mentions(forged([&](auto& b) { put(b, 120 + 256 * bvh.nodes.size(), bvh.object_count, 4); }),
                   "not below the object count"));
    CHECK(mentions(forged([&](auto& b) { put(b, 40, std::bit_cast<std::uint64_t>(-1e9), 8); }), "bounds"));
}

TEST_CASE("bvh files: a forged BVH that leaves an object out loads, and the scene's check names it", "[bvh][io]") {
    std::vector<Aabb> boxes = random_boxes(200, 4);
    std::vector<Aabb> without = boxes;
    without[77] = Aabb{};
    const WideBvh forged = build_wide_bvh(BvhBuildInput{without, 0});
    const std::vector<std::uint8_t> bytes = serialize_bvh(forged, kFingerprint);
    const WideBvh loaded = deserialize_bvh(bytes.data(), bytes.size(), kFingerprint);
    CHECK(loaded == forged);
    try {
        check_bvh(loaded, boxes);
        FAIL("a BVH without object 77 passed");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(mentions(e.what(), "object 77"));
    }
}
