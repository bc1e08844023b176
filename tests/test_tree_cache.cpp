// --tree-cache: a scene rendered twice builds its tree once; a tree file from
// another scene is refused; a damaged cache entry is rebuilt; stale temporary
// files are cleaned up; ropes exist only for the ropes traversal.
#include "scene/prepared_scene.h"
#include "tree_forgery.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <chrono>
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
    o.commit.accel = Accel::KdTree;
    o.device = "cpu";
    o.frame.width = o.frame.height = 32;
    o.commit.tree_files.cache_dir = dir;
    const RenderResult first = render(scene, o);
    CHECK_FALSE(first.stats.tree_loaded);
    const RenderResult second = render(scene, o);
    CHECK(second.stats.tree_loaded);
    CHECK(image_rmse(first.image, second.image) == 0.0);
    REQUIRE(first.stats.tree_stats);
    REQUIRE(second.stats.tree_stats);
    CHECK(first.stats.tree_stats->nodes == second.stats.tree_stats->nodes);

    // Another builder setting is another cache entry.
    o.commit.tree.builder = KdBuilderKind::Median;
    CHECK_FALSE(render(scene, o).stats.tree_loaded);

    // A damaged entry is rebuilt, not trusted.
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        std::fstream f(entry.path(), std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(40);
        f.put('\x5a');
    }
    const RenderResult third = render(scene, o);
    CHECK_FALSE(third.stats.tree_loaded);
    CHECK(image_rmse(first.image, third.image) == 0.0);
    std::filesystem::remove_all(dir);
}

TEST_CASE("tree files: a tree whose object count does not fit the scene is refused", "[kdtree][io]") {
    // A forged file: consistent in itself (checksum and structure fine), with
    // the right fingerprint, but indexing more objects than the scene has.
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json");
    RenderOptions o;
    o.commit.accel = Accel::KdTree;
    o.device = "cpu";
    o.frame.width = o.frame.height = 8;
    const auto file = std::filesystem::temp_directory_path() / "kdrt-test-forged.kdtree";
    o.commit.tree_files.save = file;
    render(scene, o);
    auto [tree, fingerprint] = test::read_saved_tree(file);
    tree.object_count += 1000;
    save_kd_tree(file, tree, fingerprint);
    o.commit.tree_files.save.reset();
    o.commit.tree_files.load = file;
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
    o.commit.accel = Accel::KdTree;
    o.frame.width = o.frame.height = 4;
    CHECK_NOTHROW(render(s, o));
}

TEST_CASE("tree files: a tree saved for one scene is refused for another", "[kdtree][io]") {
    const auto file = std::filesystem::temp_directory_path() / "kdrt-test-lens.kdtree";
    RenderOptions o;
    o.commit.accel = Accel::KdTree;
    o.device = "cpu";
    o.frame.width = o.frame.height = 8;
    o.commit.tree_files.save = file;
    render(load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json"), o);
    o.commit.tree_files.save.reset();
    o.commit.tree_files.load = file;
    try {
        render(load_scene(std::string(KDRT_SCENES_DIR) + "/2x2x4.json"), o);
        FAIL("a tree for another scene was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).find("different") != std::string::npos);
    }
    std::filesystem::remove(file);
}

TEST_CASE("tree cache: stale temporary files of killed saves are removed", "[kdtree][io][cache]") {
    const auto dir = std::filesystem::temp_directory_path() / "kdrt-test-tree-cache-stale";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const auto touch = [&](const std::string& name, std::chrono::minutes age) {
        const auto path = dir / name;
        std::ofstream(path) << "half a tree";
        std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now() - age);
        return path;
    };
    using std::chrono::minutes;
    const auto stale = touch(".0123456789abcdef-r3-sah-d0-t1-i1.5-e0.2-m1.8.kdtree.tmp-5f3Z9c", minutes(60));
    const auto fresh = touch(".0123456789abcdef-r3-sah-d0-t1-i1.5-e0.2-m1.8.kdtree.tmp-77aa01", minutes(1));
    const auto foreign = touch(".notes.kdtree.tmp-abc123", minutes(60));              // not the cache's naming
    const auto not_hex = touch(".0123456789abcdef-r3-sah.kdtree.tmp-xy", minutes(60));  // nor this
    const auto entry = touch("0123456789abcdef-r3-sah.kdtree", minutes(60));            // an old entry is kept

    RenderOptions o;
    o.commit.accel = Accel::KdTree;
    o.device = "cpu";
    o.frame.width = o.frame.height = 8;
    o.commit.tree_files.cache_dir = dir;
    render(load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json"), o);
    CHECK_FALSE(std::filesystem::exists(stale));
    CHECK(std::filesystem::exists(fresh));  // may still be in the middle of being written
    CHECK(std::filesystem::exists(foreign));
    CHECK(std::filesystem::exists(not_hex));
    CHECK(std::filesystem::exists(entry));
    std::filesystem::remove_all(dir);
}

TEST_CASE("tree files: ropes only for the ropes traversal, built after loading a rope-less file",
          "[kdtree][io][ropes]") {
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/ball-o-calypse.json");
    const auto file = std::filesystem::temp_directory_path() / "kdrt-test-ropeless.kdtree";
    RenderOptions o;
    o.commit.accel = Accel::KdTree;
    o.device = "cpu";
    o.frame.width = o.frame.height = 24;
    o.frame.want_ids = true;
    o.commit.tree_files.save = file;
    for (Traversal t : {Traversal::Stack, Traversal::Restart}) {
        o.commit.traversal = t;
        const RenderResult r = render(scene, o);
        REQUIRE(r.stats.tree_stats);
        CHECK(r.stats.tree_stats->rope_bytes == 0);
        CHECK(r.stats.tree_stats->node_bytes > 0);
        CHECK(r.stats.tree_stats->objects == scene.spheres.size() + scene.triangle_count());
    }
    const RenderResult stack = render(scene, o);
    std::ifstream in(file, std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    std::uint64_t rope_count = 0;
    for (int i = 0; i < 8; ++i) rope_count |= std::uint64_t{bytes[44 + i]} << (8 * i);
    CHECK(rope_count == 0);  // the saved file has no ropes either

    o.commit.tree_files.save.reset();
    o.commit.tree_files.load = file;
    o.commit.traversal = Traversal::Ropes;
    const RenderResult ropes = render(scene, o);
    CHECK(ropes.stats.tree_loaded);
    REQUIRE(ropes.stats.tree_stats);
    CHECK(ropes.stats.tree_stats->rope_bytes == ropes.stats.tree_stats->nodes * sizeof(KdLeafRopes));  // ropes by node id
    CHECK(ropes.ids == stack.ids);
    CHECK(image_rmse(ropes.image, stack.image) == 0.0);
    std::filesystem::remove(file);
}

TEST_CASE("tree files: a forged tree that drops an object from its leaves is refused", "[kdtree][io]") {
    // Checksum recomputed, fingerprint right, structure sound: only the
    // coverage check can tell that an object of the scene went missing. A
    // sphere (ball-o-calypse) and a triangle (insane: the last ids).
    for (const char* name : {"ball-o-calypse", "insane"}) {
        INFO(name);
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        const auto file = std::filesystem::temp_directory_path() / "kdrt-test-forged-drop.kdtree";
        RenderOptions o;
        o.commit.accel = Accel::KdTree;
        o.device = "cpu";
        o.frame.width = o.frame.height = 8;
        o.commit.tree_files.save = file;
        render(scene, o);
        auto [tree, fingerprint] = test::read_saved_tree(file);
        REQUIRE(tree.object_count > 3);
        const std::uint32_t victim = std::string(name) == "insane" ? tree.object_count - 1 : tree.object_count / 2;
        REQUIRE(test::drop_object(tree, victim) > 0);
        save_kd_tree(file, tree, fingerprint);
        o.commit.tree_files.save.reset();
        o.commit.tree_files.load = file;
        try {
            render(scene, o);
            FAIL("a tree missing object " << victim << " was accepted");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::CorruptTree);
            CHECK(std::string(e.what()).find("object " + std::to_string(victim)) != std::string::npos);
        }
        std::filesystem::remove(file);
    }
}

TEST_CASE("prepared scenes: one object's bounds are those of the whole list", "[kdtree][cache]") {
    // The coverage check of a loaded tree asks for single boxes (object_bound).
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/insane.json");
    const detail::PreparedScene p = detail::prepare_scene(scene, CommitOptions{});
    const std::vector<Aabb> all = p.object_bounds();
    REQUIRE(all.size() == p.geometry_f.object_count());
    REQUIRE(p.geometry_f.spheres.size() > 0);
    REQUIRE(p.geometry_f.triangles.size() > 0);
    for (std::uint32_t id = 0; id < all.size(); ++id) CHECK(p.object_bound(id) == all[id]);
}

TEST_CASE("prepared scenes: float keeps no double copy, and both precisions share one tree", "[kdtree][cache]") {
    const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/ball-o-calypse.json");
    CommitOptions f, d;
    d.accuracy.precision = Precision::Double;
    const detail::PreparedScene pf = detail::prepare_scene(scene, f), pd = detail::prepare_scene(scene, d);
    CHECK(pf.geometry_d.object_count() == 0);
    CHECK_THROWS_AS(pf.geometry<double>(), Error);
    REQUIRE(pd.geometry<double>().object_count() == pf.geometry_f.object_count());
    // The fingerprint and the builders' input come from the float geometry, so
    // a cached tree serves either precision.
    CHECK(pf.fingerprint == pd.fingerprint);
    const KdTree tf = build_kd_tree(pf.build_input(), {}), td = build_kd_tree(pd.build_input(), {});
    CHECK(tf == td);
    CHECK_NOTHROW(check_kd_tree_covers(tf, pd.object_bounds()));
}
