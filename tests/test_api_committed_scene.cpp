// kdrt::Device and kdrt::CommittedScene: frames after the first redo no
// build, compile or upload; shading updates keep the tree; geometry changes
// rebuild; trees given in memory are checked; ids are the ones add_* returned.
#include "api_test_scenes.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/opencl_interop.h>
#include <kdrt/ray_query.h>
#include <kdrt/render.h>
#include <kdrt/tiled_render.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

bool same_pixels(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height) return false;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            if (a.at(x, y) != b.at(x, y)) return false;
    return true;
}

bool has_opencl_device() {
    for (const DeviceInfo& d : list_devices())
        if (d.id != "cpu") return true;
    return false;
}

}  // namespace

TEST_CASE("api: Device::open names a bad device and lists what there is", "[api]") {
    try {
        (void)Device::open("nonsense");
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Device);
        CHECK(std::string(e.what()).find("'nonsense'") != std::string::npos);
    }
    const Device cpu = Device::open("CPU");
    CHECK(cpu.info().id == "cpu");
    CHECK_FALSE(cpu.is_opencl());
}

TEST_CASE("api: a negative thread count is refused, at commit and per frame", "[api]") {
    const Scene scene = kdrt_test::api_scene(2);
    RenderOptions o;
    o.frame.threads = -3;
    try {
        (void)render(scene, o);
        FAIL("FrameOptions::threads = -3 was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidArgument);
        CHECK(std::string(e.what()).find("threads is -3") != std::string::npos);
    }
    CommitOptions commit;
    commit.tree.threads = -3;  // the tree's build threads, the only ones a commit takes
    try {
        (void)CommittedScene::commit(Device::open("cpu"), scene, commit);
        FAIL("CommitOptions::tree.threads = -3 was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidArgument);
        CHECK(std::string(e.what()).find("threads") != std::string::npos);
    }
    commit = {};
    commit.bvh.threads = -3;
    CHECK_THROWS_WITH(CommittedScene::commit(Device::open("cpu"), scene, commit), Catch::Contains("threads"));
    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), scene, {});
    CHECK_THROWS_AS(c.render(o.frame), Error);
    o.frame.threads = 0;
    CHECK_NOTHROW(c.render(o.frame));
}

TEST_CASE("api: a committed scene's later frames redo no build, compile or upload", "[api]") {
    Scene scene = kdrt_test::api_scene(1);
    const Device cpu = Device::open("cpu");
    CommittedScene c = CommittedScene::commit(cpu, scene, {});
    const RenderResult first = c.render();
    CHECK(first.stats.builds == 1);
    CHECK(first.stats.build_ms > 0.0);
    CHECK(c.stats().builds == 1);
    CHECK(same_pixels(first.image, render(scene, {}).image));

    // Camera moved: the next frame is the new view, with no build.
    scene.camera.position += glm::dvec3(1.5, 0.5, 0);
    c.update(scene);
    const RenderResult second = c.render();
    CHECK(second.stats.builds == 0);
    CHECK(second.stats.compiles == 0);
    CHECK(second.stats.geometry_upload_bytes == 0);
    CHECK(second.stats.build_ms == 0.0);
    CHECK(c.stats().builds == 1);
    CHECK(c.stats().geometry_uploads == 0);  // the cpu device keeps the scene where it is
    CHECK_FALSE(same_pixels(first.image, second.image));
    CHECK(same_pixels(second.image, render(scene, {}).image));

    // Materials and lights changed: no build either.
    scene.materials[0].color = {0.2, 0.9, 0.3};
    scene.lights[0].position += glm::dvec3(-4, 0, 0);
    c.update(scene);
    const RenderResult third = c.render();
    CHECK(third.stats.builds == 0);
    CHECK(c.stats().builds == 1);
    CHECK(same_pixels(third.image, render(scene, {}).image));

    // Frame-level fields apply per frame only.
    FrameOptions small;
    small.width = 16;
    small.height = 8;
    CHECK(c.render(small).image.width == 16);
    CHECK(c.render().image.width == scene.settings.width);

    // Geometry moved: the BVH (the default structure) refit, reported by the next frame.
    const std::uint64_t before = c.geometry_fingerprint();
    scene.spheres[0].center += glm::dvec3(0.25, 0, 0);
    c.update(scene);
    CHECK(c.geometry_fingerprint() != before);
    CHECK(c.geometry_fingerprint() == geometry_fingerprint(scene));
    CHECK(c.stats().builds == 1);
    CHECK(c.stats().refits == 1);
    const RenderResult fourth = c.render();
    CHECK(fourth.stats.builds == 0);
    CHECK(fourth.stats.refits == 1);
    CHECK(same_pixels(fourth.image, render(scene, {}).image));

    // An object added: one rebuild.
    scene.add_sphere(scene.camera.look_at, 0.3, 0);
    c.update(scene);
    CHECK(c.stats().builds == 2);
    const RenderResult fifth = c.render();
    CHECK(fifth.stats.builds == 1);
    CHECK(same_pixels(fifth.image, render(scene, {}).image));
}

TEST_CASE("api: a tree built in memory is used, one of other geometry refused", "[api]") {
    const Scene scene = kdrt_test::api_scene(2);
    CommitOptions o;
    o.accel = Accel::KdTree;
    o.traversal = Traversal::Ropes;
    o.tree_files.in_memory = std::make_shared<const KdTree>(build_scene_tree(scene, o));
    CHECK(o.tree_files.in_memory->has_ropes());
    const Device cpu = Device::open("cpu");
    CommittedScene c = CommittedScene::commit(cpu, scene, o);
    CHECK(c.stats().builds == 0);
    CHECK(c.stats().tree_loads == 1);
    CHECK(c.tree() == o.tree_files.in_memory.get());  // shared, not copied
    RenderOptions fresh;
    fresh.commit.accel = Accel::KdTree;
    fresh.commit.traversal = Traversal::Ropes;
    CHECK(same_pixels(c.render().image, render(scene, fresh).image));

    CommitOptions wrong;
    wrong.accel = Accel::KdTree;
    wrong.tree_files.in_memory = std::make_shared<const KdTree>(build_scene_tree(kdrt_test::api_scene(3)));
    try {
        (void)CommittedScene::commit(cpu, scene, wrong);
        FAIL("a tree of other geometry was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        CHECK(std::string(e.what()).find("in_memory") != std::string::npos);
    }
}

TEST_CASE("api: object ids are what add_* returned, in hits and id maps", "[api]") {
    Scene s;
    s.camera.position = {0, 0, -10};
    s.camera.look_at = {0, 0, 0};
    s.settings.width = 60;
    s.settings.height = 20;
    auto m = s.add_material({});
    CHECK(s.add_sphere({-3, 0, 0}, 1.0, m) == 0u);
    CHECK(s.add_triangle({-1.5, -1.5, 0}, {1.5, -1.5, 0}, {0, 1.5, 0}, m) == 1u);
    CHECK(s.add_sphere({3, 0, 0}, 1.0, m) == 2u);
    Mesh quad;
    quad.positions = {{-1, 3, 0}, {1, 3, 0}, {1, 5, 0}};
    quad.triangles.push_back({{0, 1, 2}, {kNoNormal, kNoNormal, kNoNormal}, m});
    CHECK(s.add_mesh(quad) == 3u);

    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), s, {});
    const QueryRay to_sphere{{3, 0, -10}, 0, {0, 0, 1}, 1e30f}, to_triangle{{0, 0, -10}, 0, {0, 0, 1}, 1e30f},
        to_mesh{{0, 3.5f, -10}, 0, {0, 0, 1}, 1e30f};
    std::vector<QueryRay> rays{to_sphere, to_triangle, to_mesh};
    std::vector<QueryHit> hits(3);
    intersect(c, rays, hits);
    CHECK(hits[0].object == 2u);
    CHECK(hits[1].object == 1u);
    CHECK(hits[2].object == 3u);

    // The id map's middle row, on every device: the triangle in the middle is 1.
    std::vector<std::string> devices{"cpu"};
    if (has_opencl_device()) devices.push_back("opencl");
    for (const std::string& device : devices) {
        CAPTURE(device);
        RenderOptions o;
        o.device = device;
        o.frame.want_ids = true;
        const RenderResult r = render(s, o);
        const std::size_t row = static_cast<std::size_t>(s.settings.height / 2) * s.settings.width;
        CHECK(r.ids[row + s.settings.width / 2] == 1);
        std::vector<std::int32_t> seen;
        for (int x = 0; x < s.settings.width; ++x) {
            const std::int32_t id = r.ids[row + x];
            if (id >= 0 && (seen.empty() || seen.back() != id)) seen.push_back(id);
        }
        CHECK(seen.size() == 3);
        CHECK(seen[1] == 1);
        CHECK(seen[0] + seen[2] == 2);  // the spheres, 0 and 2, in whichever order the camera sees them
    }

    // Objects pushed directly come after the recorded ones; a removed recorded one is refused.
    Scene direct = s;
    direct.spheres.push_back({{0, -3, 0}, 0.5, m});
    const CommittedScene d = CommittedScene::commit(Device::open("cpu"), direct, {});
    std::vector<QueryRay> down{{{0, -3, -10}, 0, {0, 0, 1}, 1e30f}};
    std::vector<QueryHit> hit(1);
    intersect(d, down, hit);
    CHECK(hit[0].object == 4u);
    Scene removed = s;
    removed.spheres.pop_back();
    CHECK_THROWS_AS(CommittedScene::commit(Device::open("cpu"), removed, {}), Error);
}

namespace {

std::vector<std::string> devices_here() {
    std::vector<std::string> devices{"cpu"};
    if (has_opencl_device()) devices.push_back("opencl");
    return devices;
}

Image fresh_render(const Scene& scene, const std::string& device, Accel accel = CommitOptions{}.accel) {
    RenderOptions o;
    o.device = device;
    o.commit.accel = accel;
    return render(scene, o).image;
}

// A frame of `c` against a fresh render of `scene` on the same device.
bool renders_as_fresh(const CommittedScene& c, const Scene& scene, const std::string& device) {
    return same_pixels(c.render().image, fresh_render(scene, device));
}

}  // namespace

TEST_CASE("api: an update with the same objects leaves the geometry alone, shading is taken", "[api]") {
    for (const std::string& device : devices_here()) {
        CAPTURE(device);
        Scene scene = kdrt_test::api_scene(4);
        CommittedScene c = CommittedScene::commit(Device::open(device), scene, {});
        CHECK(c.stats().geometry_passes == 1);
        (void)c.render();

        scene.camera.position += glm::dvec3(-2.0, 1.0, 0.5);
        c.update(scene);
        CHECK(c.stats().geometry_passes == 1);
        const RenderResult moved = c.render();
        CHECK(moved.stats.builds == 0);
        CHECK(moved.stats.compiles == 0);
        CHECK(moved.stats.geometry_upload_bytes == 0);
        CHECK(same_pixels(moved.image, fresh_render(scene, device)));

        scene.materials[1].color = {0.1, 0.3, 0.9};
        scene.lights.push_back({scene.camera.position + glm::dvec3(0, 5, 0), {0.5, 0.5, 0.5}});
        scene.settings.background = {0.2, 0.1, 0.0};
        scene.settings.width = 40;
        c.update(scene);
        CHECK(c.stats().geometry_passes == 1);
        CHECK(c.stats().builds == 1);
        CHECK(c.render().image.width == 40);
        CHECK(renders_as_fresh(c, scene, device));

        // Bad shading is refused as a fresh render refuses it; the committed scene stays usable.
        Scene bad = scene;
        bad.camera.look_at = bad.camera.position;
        CHECK_THROWS_AS(c.update(bad), Error);
        CHECK_THROWS_AS(fresh_render(bad, device), Error);
        bad = scene;
        bad.materials.pop_back();  // objects use material 1
        try {
            c.update(bad);
            FAIL("a scene whose objects use a missing material was taken");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidScene);
            CHECK(std::string(e.what()).find("undefined material") != std::string::npos);
        }
        CHECK(renders_as_fresh(c, scene, device));
    }
}

TEST_CASE("api: geometry changed in place after camera-only updates is still found", "[api]") {
    // What a change costs the structure: objects that only moved refit a BVH
    // and rebuild a kd-tree; other geometry rebuilds either.
    enum class Change { Shading, Moved, Objects };
    for (const std::string& device : devices_here())
        for (const Accel accel : {Accel::Bvh, Accel::KdTree}) {
            CAPTURE(device, to_string(accel));
            Scene scene = kdrt_test::api_scene(5);
            CommitOptions options;
            options.accel = accel;
            CommittedScene c = CommittedScene::commit(Device::open(device), scene, options);
            (void)c.render();
            std::uint64_t passes = 1, builds = 1, refits = 0;
            // Each change is made to the same Scene object, after a camera-only update.
            const auto camera_then = [&](const char* what, auto change, Change kind) {
                CAPTURE(what);
                scene.camera.position += glm::dvec3(0.3, 0.0, 0.0);
                c.update(scene);
                CHECK(c.stats().geometry_passes == passes);
                (void)c.render();
                change(scene);
                c.update(scene);
                CHECK(c.stats().geometry_passes == ++passes);
                const bool refit = kind == Change::Moved && accel == Accel::Bvh;
                const bool rebuild = kind == Change::Objects || (kind == Change::Moved && !refit);
                builds += rebuild;
                refits += refit;
                CHECK(c.stats().builds == builds);
                CHECK(c.stats().refits == refits);
                const RenderResult r = c.render();
                CHECK(r.stats.builds == (rebuild ? 1u : 0u));
                if (device != "cpu") CHECK(r.stats.geometry_upload_bytes > 0);
                if (device != "cpu") CHECK(c.stats().device_bytes >= r.stats.geometry_upload_bytes);  // its buffers
                CHECK(same_pixels(r.image, fresh_render(scene, device, accel)));
                CHECK(c.geometry_fingerprint() == geometry_fingerprint(scene));
            };
            Mesh& grid = scene.meshes.back();
            camera_then("a mesh vertex moved", [](Scene& s) { s.meshes.back().positions[24].z -= 0.75; }, Change::Moved);
            camera_then("a mesh triangle dropped", [](Scene& s) {
                s.meshes.back().triangles.pop_back();
                s.added.back().count -= 1;  // the mesh's record of ids
            }, Change::Objects);
            camera_then("a sphere grown", [](Scene& s) { s.spheres[3].radius *= 1.5; }, Change::Moved);
            camera_then("a loose triangle moved", [](Scene& s) { s.triangles.positions[7].x += 0.5; }, Change::Moved);
            camera_then("a sphere added", [](Scene& s) { s.add_sphere(s.camera.look_at, 0.7, 0); }, Change::Objects);
            // Positions unchanged: the structure still fits, the triangles' materials and normals must still be taken.
            camera_then("a mesh triangle's material changed",
                        [](Scene& s) { s.meshes.back().triangles[30].material = 1; }, Change::Shading);
            camera_then("shading normals given", [&](Scene& s) {
                Mesh& m = s.meshes.back();
                m.normals = {glm::dvec3(0.3, 0.2, -1.0), glm::dvec3(-0.3, 0.1, -1.0), glm::dvec3(0.0, -0.3, -1.0)};
                for (MeshTriangle& t : m.triangles) t.n = {0, 1, 2};
            }, Change::Shading);
            CHECK(grid.normals.size() == 3);
        }
}

TEST_CASE("api: a scene without objects follows its camera through updates", "[api]") {
    Scene scene;
    scene.settings.width = 8;
    scene.settings.height = 8;
    scene.settings.background = {0.1, 0.2, 0.3};
    CommittedScene c = CommittedScene::commit(Device::open("cpu"), scene, {});
    scene.camera.position = {1e6, 0, 0};
    scene.camera.look_at = {1e6, 0, 1};
    c.update(scene);
    CHECK(renders_as_fresh(c, scene, "cpu"));
}

TEST_CASE("api: several devices leave the geometry alone on a camera move and follow a change", "[api][tiles]") {
    for (const std::string& device : devices_here()) {
        CAPTURE(device);
        Scene scene = kdrt_test::api_scene(6);
        const std::vector<Device> devices = {Device::open(device), Device::open(device)};
        CommitOptions kd;  // the BVH's: test_api_bvh.cpp
        kd.accel = Accel::KdTree;
        MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene, kd);
        const TileSize tile{16, 16};
        scene.camera.position += glm::dvec3(1.0, -0.5, 0.0);
        multi.update(scene);
        for (const CommittedScene& c : multi.scenes()) CHECK(c.stats().geometry_passes == 1);
        CHECK(same_pixels(multi.render({}, tile).image, fresh_render(scene, device, Accel::KdTree)));

        scene.meshes.back().triangles[3].material = 1;  // the same tree, other device geometry
        multi.update(scene);
        for (const CommittedScene& c : multi.scenes()) CHECK(c.stats().geometry_passes == 2);
        CHECK(multi.scenes()[0].stats().builds == 1);  // the commit's
        CHECK(multi.scenes()[1].stats().builds == 0);  // its tree was given in memory
        CHECK(same_pixels(multi.render({}, tile).image, fresh_render(scene, device, Accel::KdTree)));

        // A rebuild on the first device; the others are committed again with its tree.
        scene.triangles.positions[2].y += 0.4;
        multi.update(scene);
        CHECK(multi.scenes()[0].stats().builds == 2);
        CHECK(multi.scenes()[1].tree() == multi.scenes()[0].tree());
        CHECK(same_pixels(multi.render({}, tile).image, fresh_render(scene, device, Accel::KdTree)));
    }
}

// The triangle's SAH cost left at 0 is the device's: the cpu device, whose
// leaf test takes triangles four or eight at a time, builds with 0.3; the
// OpenCL kernels, one triangle at a time, with 0.6; build_scene_tree, which
// knows no device, with the generic 0.6. A cost given explicitly is kept.
TEST_CASE("api: a tree is built with its device's triangle cost unless one is given", "[api]") {
    Scene scene;
    const MaterialId m = scene.add_material({});
    for (int x = 0; x < 40; ++x)  // a wavy sheet of 3200 triangles and a few spheres
        for (int z = 0; z < 40; ++z) {
            auto h = [](int i, int k) { return 0.3 * std::sin(0.5 * i) * std::cos(0.4 * k); };
            const glm::dvec3 a(x, h(x, z), z), b(x + 1, h(x + 1, z), z), c(x + 1, h(x + 1, z + 1), z + 1),
                d(x, h(x, z + 1), z + 1);
            scene.add_triangle(a, b, c, m);
            scene.add_triangle(a, c, d, m);
        }
    for (int i = 0; i < 5; ++i) scene.add_sphere({4.0 + 7 * i, 1.0, 20.0}, 0.8, m);
    scene.camera.position = {20, 15, -10};
    scene.camera.look_at = {20, 0, 20};
    auto tree_with = [&](double cost) {
        CommitOptions o;
        o.tree.intersection_cost = cost;
        return build_scene_tree(scene, o);
    };
    const KdTree t03 = tree_with(0.3), t06 = tree_with(0.6);
    REQUIRE_FALSE(t03 == t06);  // the two costs do build different trees here
    CHECK(build_scene_tree(scene, {}) == t06);

    CHECK(Device::open("cpu").triangle_cost() == 0.3);
    CommitOptions kd;
    kd.accel = Accel::KdTree;
    const CommittedScene cpu = CommittedScene::commit(Device::open("cpu"), scene, kd);
    REQUIRE(cpu.tree());
    CHECK(*cpu.tree() == t03);
    CommitOptions given = kd;
    given.tree.intersection_cost = 0.6;
    CHECK(*CommittedScene::commit(Device::open("cpu"), scene, given).tree() == t06);
    if (has_opencl_device()) {
        CHECK(Device::open("opencl").triangle_cost() == 0.6);
        const CommittedScene cl = CommittedScene::commit(Device::open("opencl"), scene, kd);
        REQUIRE(cl.tree());
        CHECK(*cl.tree() == t06);
    }
}

// A moved-from handle holds nothing: every call on it, and every call given
// it, is a kdrt::Error(InvalidArgument) saying so, never a crash.
TEST_CASE("api: a moved-from Device, CommittedScene or MultiDeviceScene throws from every call", "[api]") {
    const auto moved_from = [](const std::function<void()>& call) {
        try {
            call();
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(std::string(e.what()).find("moved from") != std::string::npos);
            return true;
        }
        return false;
    };
    const Scene scene = kdrt_test::api_scene(2);

    Device device = Device::open("cpu");
    const Device kept = std::move(device);
    CHECK(kept.info().id == "cpu");
    CHECK(moved_from([&] { (void)device.info(); }));
    CHECK(moved_from([&] { (void)device.is_opencl(); }));
    CHECK(moved_from([&] { (void)device.triangle_cost(); }));
    CHECK(moved_from([&] { (void)CommittedScene::commit(device, scene); }));
    const std::vector<Device> with_moved = {kept, device};
    CHECK(moved_from([&] { (void)MultiDeviceScene::commit(with_moved, scene); }));

    CommittedScene committed = CommittedScene::commit(kept, scene);
    const CommittedScene taken = std::move(committed);
    CHECK(taken.render().image.width == scene.settings.width);
    std::vector<QueryRay> rays{{{0, 0, -10}, 0, {0, 0, 1}, 1e30f}};
    std::vector<QueryHit> hits(1);
    std::vector<std::uint8_t> blocked(1);
    CHECK(moved_from([&] { committed.update(scene); }));
    CHECK(moved_from([&] { (void)committed.render(); }));
    CHECK(moved_from([&] { (void)committed.stats(); }));
    CHECK(moved_from([&] { (void)committed.tree(); }));
    CHECK(moved_from([&] { (void)committed.geometry_fingerprint(); }));
    CHECK(moved_from([&] { (void)committed.device(); }));
    CHECK(moved_from([&] { intersect(committed, rays, hits); }));
    CHECK(moved_from([&] { occluded(committed, rays, blocked); }));
    CHECK(moved_from([&] { intersect(committed, static_cast<cl_mem>(nullptr), static_cast<cl_mem>(nullptr), 1); }));
    CHECK(moved_from([&] { occluded(committed, static_cast<cl_mem>(nullptr), static_cast<cl_mem>(nullptr), 1); }));
    const std::vector<CommittedScene> scenes = {taken, committed};
    CHECK(moved_from([&] {
        (void)render_tiles(scenes, {}, [] { return std::optional<PixelRect>(); },
                           [](std::size_t, const PixelRect&, RenderResult&&) {});
    }));

    const std::vector<Device> two = {kept, kept};
    MultiDeviceScene multi = MultiDeviceScene::commit(two, scene);
    const MultiDeviceScene multi_taken = std::move(multi);
    CHECK(multi_taken.scenes().size() == 2);
    CHECK(multi.scenes().empty());
    CHECK(moved_from([&] { multi.update(scene); }));
    CHECK(moved_from([&] { (void)multi.render(); }));
}
