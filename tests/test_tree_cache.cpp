// --tree-cache: a scene rendered twice builds its tree once; a tree file from
// another scene is refused; a damaged cache entry is rebuilt.
#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

using namespace kdrt;

TEST_CASE("tree cache: the second render loads the tree instead of building it", "[kdtree][io][cache]") {
    const auto dir = std::filesystem::temp_directory_path() / "kdrt-test-tree-cache";
    std::filesystem::remove_all(dir);
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/purple-wall.json");
    RenderOptions o;
    o.device = "cpu";
    o.width = o.height = 32;
    o.tree_cache_dir = dir;
    const RenderResult first = render(scene, o);
    CHECK_FALSE(first.tree_loaded);
    const RenderResult second = render(scene, o);
    CHECK(second.tree_loaded);
    CHECK(image_rmse(first.image, second.image) == 0.0);
    REQUIRE(first.tree_stats);
    REQUIRE(second.tree_stats);
    CHECK(first.tree_stats->nodes == second.tree_stats->nodes);

    // Another builder setting is another cache entry.
    o.tree.builder = KdBuilderKind::Median;
    CHECK_FALSE(render(scene, o).tree_loaded);

    // A damaged entry is rebuilt, not trusted.
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        std::fstream f(entry.path(), std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(40);
        f.put('\x5a');
    }
    const RenderResult third = render(scene, o);
    CHECK_FALSE(third.tree_loaded);
    CHECK(image_rmse(first.image, third.image) == 0.0);
    std::filesystem::remove_all(dir);
}

TEST_CASE("tree files: a tree whose object count does not fit the scene is refused", "[kdtree][io]") {
    // A forged file: consistent in itself (checksum and structure fine), with
    // the right fingerprint, but indexing more objects than the scene has.
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json");
    RenderOptions o;
    o.device = "cpu";
    o.width = o.height = 8;
    const auto file = std::filesystem::temp_directory_path() / "kdrt-test-forged.kdtree";
    o.save_tree = file;
    render(scene, o);
    std::ifstream in(file, std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    std::uint64_t fingerprint = 0;
    for (int i = 0; i < 8; ++i) fingerprint |= std::uint64_t{bytes[108 + i]} << (8 * i);
    KdTree tree = deserialize_kd_tree(bytes.data(), bytes.size(), fingerprint);
    tree.object_count += 1000;
    save_kd_tree(file, tree, fingerprint);
    o.save_tree.reset();
    o.load_tree = file;
    try {
        render(scene, o);
        FAIL("a tree for more objects than the scene has was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).find("objects") != std::string::npos);
    }
    std::filesystem::remove(file);
}

TEST_CASE("scene files: a ray depth beyond the supported maximum is refused", "[scene]") {
    Scene s = load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json");
    s.settings.max_depth = KDRT_MAX_RAY_DEPTH + 1;
    CHECK_THROWS_AS(render(s, RenderOptions{}), Error);
    s.settings.max_depth = KDRT_MAX_RAY_DEPTH;
    RenderOptions o;
    o.width = o.height = 4;
    CHECK_NOTHROW(render(s, o));
}

TEST_CASE("tree files: a tree saved for one scene is refused for another", "[kdtree][io]") {
    const auto file = std::filesystem::temp_directory_path() / "kdrt-test-lens.kdtree";
    RenderOptions o;
    o.device = "cpu";
    o.width = o.height = 8;
    o.save_tree = file;
    render(load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json"), o);
    o.save_tree.reset();
    o.load_tree = file;
    try {
        render(load_scene(std::string(KDRT_SCENES_DIR) + "/2x2x4.json"), o);
        FAIL("a tree for another scene was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).find("different") != std::string::npos);
    }
    std::filesystem::remove(file);
}
