// The BVH behind the public API (CommitOptions::accel = Accel::Bvh) on the cpu
// device: the pictures and hits of the kd-tree, refits of moved geometry,
// cancellable updates, files and the cache, several devices sharing one build.
#include "api_test_scenes.h"
#include "temp_dir.h"
#include "wavy_sheet.h"

#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/ray_query.h>
#include <kdrt/scene_loader.h>
#include <kdrt/tiled_render.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

CommitOptions bvh_options() {
    CommitOptions o;
    o.accel = Accel::Bvh;
    return o;
}

CommitOptions kd_options() {
    CommitOptions o;
    o.accel = Accel::KdTree;
    return o;
}

// A tessellated wavy sheet of n x n quads, with vertices displaced by `wave`.
Scene sheet(int n, double wave) {
    Scene s;
    s.camera.position = {0.5, 0.5, -3};
    s.camera.look_at = {0.5, 0.5, 0};
    s.settings.width = s.settings.height = 32;
    const MaterialId m = s.add_material({});
    s.add_light({{0.5, 2, -2}, {1, 1, 1}});
    kdrt_test::add_wavy_sheet(s, n, wave, m);
    return s;
}

// Rays from in front of the sheet, random directions into it.
std::vector<QueryRay> rays_at_sheet(std::uint32_t seed, int count) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.2f, 1.2f);
    std::vector<QueryRay> rays;
    for (int i = 0; i < count; ++i) {
        const float ox = u(rng), oy = u(rng), tx = u(rng), ty = u(rng);
        rays.push_back({{ox, oy, -2.0f}, 0.0f, {tx - ox, ty - oy, 2.0f}, std::numeric_limits<float>::infinity()});
    }
    return rays;
}

// The hits of `rays` on `scene` with no structure at all: every object tested.
std::vector<QueryHit> brute_force_hits(const Scene& scene, const std::vector<QueryRay>& rays) {
    CommitOptions o;
    o.traversal = Traversal::None;
    const CommittedScene all = CommittedScene::commit(Device::open("cpu"), scene, o);
    CHECK(all.stats().device_bytes == 0);  // no structure, nothing packed
    std::vector<QueryHit> hits(rays.size());
    intersect(all, rays, hits);
    return hits;
}

void check_same_hits(const std::vector<QueryHit>& a, const std::vector<QueryHit>& b) {
    REQUIRE(a.size() == b.size());
    std::size_t hit = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        CAPTURE(i);
        REQUIRE(a[i].object == b[i].object);
        if (a[i].object == KDRT_NO_HIT) continue;
        CHECK(a[i].t == b[i].t);
        ++hit;
    }
    CHECK(hit > a.size() / 4);
}

}  // namespace

TEST_CASE("bvh: the study's scenes render the kd-tree's pictures and id maps", "[api][bvh]") {
    const Device cpu = Device::open("cpu");
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"}) {
        CAPTURE(name);
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        FrameOptions frame;
        frame.width = frame.height = 64;
        frame.want_ids = true;
        const RenderResult kd = CommittedScene::commit(cpu, scene, kd_options()).render(frame);
        const RenderResult bvh = CommittedScene::commit(cpu, scene, bvh_options()).render(frame);
        const IdMapComparison c = compare_id_maps(kd, bvh);
        INFO(c.summary());
        CHECK(c.ok());
        REQUIRE(bvh.stats.bvh_stats);
        CHECK_FALSE(bvh.stats.tree_stats);
        CHECK(bvh.stats.bvh_stats->objects == scene.object_count());
        CHECK(bvh.stats.builds == 1);
    }
}

TEST_CASE("bvh: update() refits moved vertices, and the refit BVH finds brute force's hits", "[api][bvh]") {
    const Device cpu = Device::open("cpu");
    CommittedScene committed = CommittedScene::commit(cpu, sheet(24, 0.05), bvh_options());
    REQUIRE(committed.stats().builds == 1);
    committed.render();  // reports the commit's build
    const std::vector<QueryRay> rays = rays_at_sheet(3, 2000);

    const Scene moved = sheet(24, 0.15);  // the same triangles, every vertex moved
    committed.update(moved);
    CHECK(committed.stats().refits == 1);
    CHECK(committed.stats().builds == 1);
    std::vector<QueryHit> hits(rays.size());
    intersect(committed, rays, hits);
    check_same_hits(hits, brute_force_hits(moved, rays));
    const RenderResult frame = committed.render();
    CHECK(frame.stats.refits == 1);
    CHECK(frame.stats.builds == 0);

    // Vertices flung apart: the refit hierarchy's SAH cost grows past the threshold, and it is rebuilt.
    Scene torn = moved;
    for (std::size_t i = 0; i < torn.meshes[0].positions.size(); i += 2) torn.meshes[0].positions[i].z += 40.0;
    committed.update(torn);
    CHECK(committed.stats().builds == 2);
    CHECK(committed.stats().refits == 1);
    intersect(committed, rays, hits);
    check_same_hits(hits, brute_force_hits(torn, rays));

    // Other objects (one triangle more): a build, not a refit.
    Scene grown = moved;
    grown.add_triangle({0, 0, 1}, {1, 0, 1}, {0, 1, 1}, 0);
    committed.update(grown);
    CHECK(committed.stats().builds == 3);
    intersect(committed, rays, hits);
    check_same_hits(hits, brute_force_hits(grown, rays));
}

// The cpu device copies every BVH leaf's triangles into blocks, found by node
// slot, whatever the mesh's size (the kd-tree's leaves only up to 65,536
// references): a mesh above that, with spheres in some leaves, refit too.
TEST_CASE("bvh: a big mesh's packed leaves find brute force's hits, before and after a refit", "[api][bvh]") {
    const Device cpu = Device::open("cpu");
    Scene scene = sheet(190, 0.05);  // 72,200 triangles
    for (int i = 0; i < 40; ++i) scene.add_sphere({0.025 * i, 0.5, -0.01 * (i % 3)}, 0.004, 0);
    CommittedScene committed = CommittedScene::commit(cpu, scene, bvh_options());
    const std::vector<QueryRay> rays = rays_at_sheet(11, 600);
    std::vector<QueryHit> hits(rays.size());
    intersect(committed, rays, hits);
    check_same_hits(hits, brute_force_hits(scene, rays));
    // The packed copy holds every triangle's vertices once, in floats, and a copy of the nodes; its blocks'
    // unused lanes and 4-byte ids (at most a whole block per leaf) bound it from above.
    const std::optional<BvhStats> bvh = committed.bvh_stats();
    REQUIRE(bvh);
    const std::uint64_t packed = committed.stats().device_bytes;
    const std::uint64_t triangles = 190 * 190 * 2;
    CHECK(packed >= bvh->node_bytes + triangles * 9 * sizeof(float));
    CHECK(packed <= bvh->node_bytes + (triangles + 8 * bvh->leaves) * 10 * sizeof(float) + 64 * bvh->leaves);

    Scene moved = sheet(190, 0.12);
    for (int i = 0; i < 40; ++i) moved.add_sphere({0.025 * i, 0.5, -0.01 * (i % 3)}, 0.004, 0);
    committed.update(moved);
    REQUIRE(committed.stats().refits == 1);
    CHECK(committed.stats().device_bytes == packed);  // refilled in place
    intersect(committed, rays, hits);
    const std::vector<QueryHit> truth = brute_force_hits(moved, rays);
    check_same_hits(hits, truth);
    // Any hit before, and not before, the closest.
    std::vector<QueryRay> shorter = rays;
    for (std::size_t i = 0; i < rays.size(); ++i)
        shorter[i].t_max = truth[i].object == KDRT_NO_HIT ? 10.0f : truth[i].t * 0.999f;
    std::vector<std::uint8_t> blocked(rays.size()), blocked_all(rays.size());
    occluded(committed, shorter, blocked);
    occluded(committed, rays, blocked_all);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        CAPTURE(i);
        CHECK(blocked[i] == 0);
        CHECK(blocked_all[i] == (truth[i].object != KDRT_NO_HIT));
    }
}

TEST_CASE("bvh: update() reports its progress and can be cancelled", "[api][bvh][cancel]") {
    const Device cpu = Device::open("cpu");
    CommittedScene committed = CommittedScene::commit(cpu, sheet(64, 0.05), bvh_options());
    Scene other = sheet(64, 0.05);
    other.add_sphere({0.5, 0.5, -1}, 0.1, 0);  // a new object: a rebuild with progress
    double last = -1.0;
    int calls = 0;
    committed.update(other, [&](double f) {
        CHECK(f >= 0.0);
        CHECK(f <= 1.0);
        last = f;
        ++calls;
        return true;
    });
    CHECK(calls > 0);
    CHECK(last >= 0.0);
    const Scene third = sheet(80, 0.05);
    CHECK_THROWS_MATCHES(committed.update(third, [](double) { return false; }), Error,
                         Catch::Matchers::Predicate<Error>([](const Error& e) { return e.code() == ErrorCode::Cancelled; }));
    CHECK_THROWS_WITH(committed.render(), Catch::Contains("update() it again"));
    CHECK(committed.stats().device_bytes == 0);  // nothing kept until updated again
    committed.update(third);
    CHECK(committed.stats().device_bytes > 0);
    CHECK_NOTHROW(committed.render());
    // A cancelled refit (the same objects, moved) leaves nothing stale behind either.
    const std::uint64_t refits = committed.stats().refits;
    const Scene moved = sheet(80, 0.07);
    CHECK_THROWS_AS(committed.update(moved, [](double) { return false; }), Error);
    CHECK_THROWS_WITH(committed.render(), Catch::Contains("update() it again"));
    committed.update(moved);
    CHECK(committed.stats().refits == refits + 1);
    CHECK_NOTHROW(committed.render());
}

TEST_CASE("bvh: files and the cache keep BVHs apart from kd-trees", "[api][bvh][io][cache]") {
    const test::TempDir dir("kdrt-bvh-files");
    const Device cpu = Device::open("cpu");
    const Scene scene = kdrt_test::api_scene(5);

    CommitOptions save = bvh_options();
    save.tree_files.save = dir.path / "scene.bvh";
    CommittedScene::commit(cpu, scene, save);
    CommitOptions load = bvh_options();
    load.tree_files.load = dir.path / "scene.bvh";
    const CommittedScene loaded = CommittedScene::commit(cpu, scene, load);
    CHECK(loaded.stats().tree_loads == 1);
    CHECK(loaded.stats().builds == 0);

    // A kd-tree file for a BVH commit, and the other way round: refused, naming the kind.
    CommitOptions kd_save = kd_options();
    kd_save.tree_files.save = dir.path / "scene.kdtree";
    CommittedScene::commit(cpu, scene, kd_save);
    CommitOptions wrong = bvh_options();
    wrong.tree_files.load = dir.path / "scene.kdtree";
    CHECK_THROWS_WITH(CommittedScene::commit(cpu, scene, wrong), Catch::Contains("kd-tree"));
    CommitOptions wrong_kd = kd_options();
    wrong_kd.tree_files.load = dir.path / "scene.bvh";
    CHECK_THROWS_WITH(CommittedScene::commit(cpu, scene, wrong_kd), Catch::Contains("BVH"));
    // A BVH file of other geometry is refused.
    CommitOptions other = load;
    CHECK_THROWS_AS(CommittedScene::commit(cpu, kdrt_test::api_scene(6), other), Error);

    // One cache directory holds both kinds; the second commit of each loads.
    CommitOptions cached_bvh = bvh_options(), cached_kd = kd_options();
    cached_bvh.tree_files.cache_dir = cached_kd.tree_files.cache_dir = dir.path / "cache";
    CHECK(CommittedScene::commit(cpu, scene, cached_bvh).stats().builds == 1);
    CHECK(CommittedScene::commit(cpu, scene, cached_kd).stats().builds == 1);
    CHECK(CommittedScene::commit(cpu, scene, cached_bvh).stats().tree_loads == 1);
    CHECK(CommittedScene::commit(cpu, scene, cached_kd).stats().tree_loads == 1);
}

TEST_CASE("bvh: the default structure, and the kd-tree's traversals refused with it", "[api][bvh]") {
    const Device cpu = Device::open("cpu");
    const Scene scene = kdrt_test::api_scene(5);
    CHECK(CommitOptions{}.accel == Accel::Bvh);
    const CommittedScene committed = CommittedScene::commit(cpu, scene);
    CHECK(committed.bvh_stats());
    CHECK_FALSE(committed.tree());
    CommitOptions ropes;
    ropes.traversal = Traversal::Ropes;
    CHECK_THROWS_WITH(CommittedScene::commit(cpu, scene, ropes), Catch::Contains("Accel::KdTree"));
}

TEST_CASE("bvh: only the stack traversal and none, and no kd-tree in memory", "[api][bvh]") {
    const Device cpu = Device::open("cpu");
    const Scene scene = kdrt_test::api_scene(5);
    for (Traversal t : {Traversal::Restart, Traversal::Ropes, Traversal::ShortStack}) {
        CommitOptions o = bvh_options();
        o.traversal = t;
        CHECK_THROWS_WITH(CommittedScene::commit(cpu, scene, o), Catch::Contains("BVH") && Catch::Contains(to_string(t)));
    }
    CommitOptions none = bvh_options();
    none.traversal = Traversal::None;
    CHECK(CommittedScene::commit(cpu, scene, none).stats().builds == 0);
    CommitOptions in_memory = bvh_options();
    in_memory.tree_files.in_memory = std::make_shared<const KdTree>(build_scene_tree(scene));
    CHECK_THROWS_WITH(CommittedScene::commit(cpu, scene, in_memory), Catch::Contains("in_memory"));
}

TEST_CASE("bvh: several devices share one build, and follow a refit", "[api][bvh][tiles]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu")};
    MultiDeviceScene scenes = MultiDeviceScene::commit(devices, sheet(24, 0.05), bvh_options());
    std::uint64_t builds = 0;
    for (const CommittedScene& s : scenes.scenes()) builds += s.stats().builds;
    CHECK(builds == 1);
    FrameOptions frame;
    frame.want_ids = true;
    const Scene moved = sheet(24, 0.15);
    scenes.update(moved);
    const RenderResult tiled = scenes.render(frame, {8, 8});
    const RenderResult alone = CommittedScene::commit(devices[0], moved, bvh_options()).render(frame);
    CHECK(tiled.ids == alone.ids);
    CHECK(tiled.image.rgb == alone.image.rgb);
    REQUIRE(tiled.stats.bvh_stats);  // the tiled frame reports the (refit) hierarchy, as one device does
    CHECK(tiled.stats.bvh_stats->nodes == scenes.scenes()[0].bvh_stats()->nodes);
}
