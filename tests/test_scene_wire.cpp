// The scene wire format (kdrt/scene_wire.h): exact round trips of the five
// scenes and of a programmatic scene whose object ids are not FORMAT.md's
// order, and every kind of damage rejected with kdrt::Error(InvalidScene).
#include <catch2/catch.hpp>
#include "api_test_scenes.h"

#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>
#include <kdrt/scene_wire.h>

#include <xxhash.h>

#include <bit>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

using namespace kdrt;

namespace {

constexpr std::size_t kHeaderSize = 28, kChecksumOffset = 20;

// The format's checksum recomputed from its documentation, to forge messages.
void reseal(std::vector<std::uint8_t>& bytes) {
    std::vector<std::uint8_t> covered(bytes.begin(), bytes.begin() + kChecksumOffset);
    covered.insert(covered.end(), bytes.begin() + kHeaderSize, bytes.end());
    const std::uint64_t h = XXH3_64bits(covered.data(), covered.size());
    for (int i = 0; i < 8; ++i) bytes[kChecksumOffset + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

// Objects added out of FORMAT.md's order: a triangle, spheres, a mesh, a triangle.
Scene out_of_order_scene() {
    Scene s;
    s.name = "ids";
    s.camera.position = {0, 0, -6};
    s.settings.width = 24;
    s.settings.height = 16;
    const MaterialId m = s.add_material({});
    s.add_light({{2, 4, -4}, {1, 1, 1}});
    s.add_triangle({-2, -1, 0}, {-1, -1, 0}, {-1.5, 0, 0}, m);
    s.add_sphere({0.5, 0.5, 0}, 0.5, m);
    s.add_sphere({-0.5, 0.8, 0.3}, 0.3, m);
    Mesh quad;
    quad.positions = {{0, -1, 0.5}, {2, -1, 0.5}, {2, 0, 0.5}, {0, 0, 0.5}};
    quad.normals = {{0, 0, -1}};
    quad.triangles = {{{0, 1, 2}, {0, 0, 0}, m}, {{0, 2, 3}, {kNoNormal, kNoNormal, kNoNormal}, m}};
    s.add_mesh(quad);
    s.add_triangle({1, 1, 0}, {2, 1, 0}, {1.5, 1.5, 0}, m);
    return s;
}

void require_same_scene(const Scene& a, const Scene& b) {
    // The encoding is of every field, so equal bytes are equal scenes.
    REQUIRE(serialize_scene(a) == serialize_scene(b));
    REQUIRE(a.name == b.name);
    REQUIRE(a.object_count() == b.object_count());
    REQUIRE(a.materials.size() == b.materials.size());
    REQUIRE(a.added.size() == b.added.size());
    for (std::size_t i = 0; i < a.added.size(); ++i) {
        REQUIRE(a.added[i].kind == b.added[i].kind);
        REQUIRE(a.added[i].first == b.added[i].first);
        REQUIRE(a.added[i].count == b.added[i].count);
    }
}

}  // namespace

TEST_CASE("scene wire format round-trips the five scenes exactly", "[scene][io][wire]") {
    for (const char* name : {"2x2x4", "ball-o-calypse", "insane", "lens", "purple-wall"}) {
        INFO(name);
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        const std::vector<std::uint8_t> bytes = serialize_scene(scene);
        const Scene back = deserialize_scene(bytes.data(), bytes.size());
        require_same_scene(scene, back);
        REQUIRE(back.camera.position == scene.camera.position);
        REQUIRE(back.settings.max_depth == scene.settings.max_depth);
        REQUIRE(back.settings.background == scene.settings.background);
        REQUIRE(back.triangle_count() == scene.triangle_count());
        if (!scene.spheres.empty()) REQUIRE(back.spheres.back().radius == scene.spheres.back().radius);
        if (!scene.materials.empty()) REQUIRE(back.materials.back().name == scene.materials.back().name);
    }
}

TEST_CASE("scene wire format keeps programmatic object ids", "[scene][io][wire]") {
    for (const Scene& scene : {out_of_order_scene(), kdrt_test::api_scene(3)}) {
        const std::vector<std::uint8_t> bytes = serialize_scene(scene);
        const Scene back = deserialize_scene(bytes.data(), bytes.size());
        require_same_scene(scene, back);
        // The id map reports the add_* ids on both sides.
        RenderOptions o;
        o.device = "cpu";
        o.frame.want_ids = true;
        o.frame.threads = 1;
        const RenderResult a = render(scene, o), b = render(back, o);
        REQUIRE(a.ids == b.ids);
        REQUIRE(a.image.rgb == b.image.rgb);
    }
    // The out-of-order scene's first object, the triangle, keeps id 0.
    const Scene s = out_of_order_scene();
    const std::vector<std::uint8_t> bytes = serialize_scene(s);
    REQUIRE(deserialize_scene(bytes.data(), bytes.size()).added.front().kind == AddedObjects::Kind::Triangles);
}

TEST_CASE("scene wire bytes truncated at every length are rejected", "[scene][io][wire]") {
    const std::vector<std::uint8_t> bytes = serialize_scene(out_of_order_scene());
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        INFO(n);
        REQUIRE_THROWS_AS(deserialize_scene(bytes.data(), n, "msg"), Error);
    }
}

TEST_CASE("scene wire bytes with a flipped byte are rejected", "[scene][io][wire]") {
    const std::vector<std::uint8_t> good = serialize_scene(out_of_order_scene());
    for (std::size_t i = 0; i < good.size(); ++i) {
        INFO(i);
        std::vector<std::uint8_t> bytes = good;
        bytes[i] ^= 0x10;
        try {
            deserialize_scene(bytes.data(), bytes.size(), "msg");
            FAIL("accepted");
        } catch (const Error& e) {
            REQUIRE(e.code() == ErrorCode::InvalidScene);
            REQUIRE(std::string(e.what()).rfind("msg: ", 0) == 0);
        }
    }
}

TEST_CASE("scene wire bytes with forged counts or values are refused", "[scene][io][wire]") {
    const Scene scene = out_of_order_scene();
    std::vector<std::uint8_t> bytes = serialize_scene(scene);
    // The name's length (the payload's first field) claims more than there is.
    std::vector<std::uint8_t> forged = bytes;
    for (int i = 0; i < 8; ++i) forged[kHeaderSize + i] = 0xff;
    reseal(forged);
    REQUIRE_THROWS_WITH(deserialize_scene(forged.data(), forged.size()), Catch::Contains("do not fit"));

    // A sealed message of a scene that validate() refuses.
    Scene bad = scene;
    bad.spheres[0].radius = -1.0;
    bytes = serialize_scene(bad);
    REQUIRE_THROWS_WITH(deserialize_scene(bytes.data(), bytes.size(), "msg"), Catch::Contains("radius"));

    // `added` naming an object the scene does not have.
    bad = scene;
    bad.spheres.pop_back();
    bytes = serialize_scene(bad);
    REQUIRE_THROWS_AS(deserialize_scene(bytes.data(), bytes.size()), Error);

    // Another version, and bytes that are no scene.
    bytes = serialize_scene(scene);
    bytes[8] = 2;
    reseal(bytes);
    REQUIRE_THROWS_WITH(deserialize_scene(bytes.data(), bytes.size()), Catch::Contains("version 2"));
    const std::vector<std::uint8_t> junk(64, 0x41);
    REQUIRE_THROWS_WITH(deserialize_scene(junk.data(), junk.size()), Catch::Contains("bad magic"));
}

TEST_CASE("scene wire bytes carrying NaN, infinite or out-of-range values are refused by name", "[scene][io][wire]") {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    // Sealed (serialize_scene encodes without validating): only validation stands in the way.
    const std::vector<std::pair<std::string, std::function<void(Scene&)>>> damage = {
        {"camera.position", [&](Scene& s) { s.camera.position.y = nan; }},
        {"camera.look_at", [&](Scene& s) { s.camera.look_at.x = inf; }},
        {"camera.fov_y", [&](Scene& s) { s.camera.fov_y = nan; }},
        {"settings.background", [&](Scene& s) { s.settings.background.z = nan; }},
        {"settings.ambient", [&](Scene& s) { s.settings.ambient.x = -inf; }},
        {"settings.width", [&](Scene& s) { s.settings.width = 0; }},
        {"settings.max_depth", [&](Scene& s) { s.settings.max_depth = 1 << 30; }},
        {"settings.samples", [&](Scene& s) { s.settings.samples = -4; }},
        {".diffuse", [&](Scene& s) { s.materials[0].diffuse = nan; }},
        {".ior", [&](Scene& s) { s.materials[0].ior = inf; }},
        {"lights[0].color", [&](Scene& s) { s.lights[0].color.y = nan; }},
        {"spheres[1].radius", [&](Scene& s) { s.spheres[1].radius = nan; }},
        {"spheres[0].center", [&](Scene& s) { s.spheres[0].center.x = inf; }},
        {"triangles.positions[1]", [&](Scene& s) { s.triangles.positions[1].z = nan; }},
        {"meshes[0].normals[0]", [&](Scene& s) { s.meshes[0].normals[0].x = nan; }},
        {"meshes[0].positions[3]", [&](Scene& s) { s.meshes[0].positions[3].y = -inf; }},
    };
    for (const auto& [field, apply] : damage) {
        INFO(field);
        Scene bad = out_of_order_scene();
        apply(bad);
        const std::vector<std::uint8_t> bytes = serialize_scene(bad);
        try {
            deserialize_scene(bytes.data(), bytes.size(), "msg");
            FAIL("accepted");
        } catch (const Error& e) {
            REQUIRE(e.code() == ErrorCode::InvalidScene);
            REQUIRE_THAT(e.what(), Catch::StartsWith("msg: ") && Catch::Contains(field));
        }
    }
}

TEST_CASE("scene wire counts of inner arrays and added records larger than the bytes are refused", "[scene][io][wire]") {
    // A mesh with no positions, normals or triangles and a scene of nothing else: the mesh's
    // position count is the u64 right after the meshes' count, 8 x 4 + 8 bytes before the end
    // of the payload (three empty arrays and an empty `added`).
    Scene s = out_of_order_scene();
    s.spheres.clear();
    s.triangles = {};
    s.meshes = {Mesh{}};
    s.added.clear();
    std::vector<std::uint8_t> bytes = serialize_scene(s);
    REQUIRE_NOTHROW(deserialize_scene(bytes.data(), bytes.size()));
    const std::size_t positions = bytes.size() - 8 * 4;  // mesh positions count, normals, triangles, added
    for (const std::uint64_t count : {std::uint64_t{2}, std::uint64_t{1} << 40, ~std::uint64_t{0}}) {
        INFO(count);
        std::vector<std::uint8_t> forged = bytes;
        for (int i = 0; i < 8; ++i) forged[positions + i] = static_cast<std::uint8_t>(count >> (8 * i));
        reseal(forged);
        REQUIRE_THROWS_WITH(deserialize_scene(forged.data(), forged.size()), Catch::Contains("do not fit"));
    }
    // `added` naming spheres past the end, with first + count wrapping a 32-bit sum.
    s = out_of_order_scene();
    s.added = {{AddedObjects::Kind::Spheres, 0xFFFFFFFFu, 2}};
    bytes = serialize_scene(s);
    REQUIRE_THROWS_AS(deserialize_scene(bytes.data(), bytes.size()), Error);
    s.added = {{AddedObjects::Kind::Mesh, 7, 2}};
    bytes = serialize_scene(s);
    REQUIRE_THROWS_AS(deserialize_scene(bytes.data(), bytes.size()), Error);
}
