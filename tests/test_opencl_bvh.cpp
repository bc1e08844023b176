// The wide BVH on OpenCL (CommitOptions::accel = Accel::Bvh, cl/traverse_bvh.cl)
// through the public API, on PoCL in CI: the five scenes' pictures and id
// maps against the cpu device's BVH for every schedule, the BVH shared by a
// cpu and an OpenCL device and refit on both, the traversal stack reported,
// and the traversals the BVH has not. Ray queries and the GPU kernels are
// checked in test_opencl_queries.cpp. Skips with a warning without OpenCL.
#include "have_opencl.h"
#include "opencl/cl_devices.h"
#include "wavy_sheet.h"

#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>
#include <kdrt/tiled_render.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

using kdrt_test::have_opencl;

Scene scene_named(const std::string& name) { return load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json"); }

CommitOptions bvh_options() {
    CommitOptions o;
    o.accel = Accel::Bvh;
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    return o;
}

// A tessellated wavy sheet of n x n quads, its vertices displaced by `wave`.
Scene sheet(int n, double wave) {
    Scene s;
    s.camera.position = {0.5, 0.5, -3};
    s.camera.look_at = {0.5, 0.5, 0};
    s.settings.width = s.settings.height = 32;
    const MaterialId m = s.add_material({});
    s.add_light({{0.5, 2, -2}, {1, 1, 1}});
    s.add_sphere({0.5, 0.5, -0.4}, 0.15, m);
    kdrt_test::add_wavy_sheet(s, n, wave, m);
    return s;
}

}  // namespace

// The bounds of the kd-tree's OpenCL tests (test_opencl_render.cpp): image
// RMSE below 4e-3, id mismatches only at silhouettes or ties, at most 1%.
TEST_CASE("opencl bvh: the five scenes render the cpu device's BVH pictures for every schedule", "[opencl][bvh][render]") {
    if (!have_opencl()) return;
    const Device cpu = Device::open("cpu"), cl = Device::open("opencl");
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"}) {
        const Scene scene = scene_named(name);
        FrameOptions frame;
        frame.width = frame.height = 64;
        frame.want_ids = true;
        const RenderResult ref = CommittedScene::commit(cpu, scene, bvh_options()).render(frame);
        const CommittedScene on_cl = CommittedScene::commit(cl, scene, bvh_options());
        for (Schedule s : {Schedule::Persistent, Schedule::Wavefront, Schedule::Plain}) {
            INFO(name << ", schedule " << to_string(s));
            frame.opencl.schedule = s;
            const RenderResult got = on_cl.render(frame);
            const IdMapComparison c = compare_id_maps(ref, got);
            INFO(c.summary());
            CHECK(c.unexplained == 0);
            CHECK(c.mismatches <= ref.ids.size() / 100);
            CHECK(image_rmse(ref.image, got.image) < 4e-3);
            CHECK(got.stats.rays.camera == ref.stats.rays.camera);
            CHECK(got.stats.opencl.kernel_options.find("-DKDRT_TRAVERSAL=5") != std::string::npos);
            REQUIRE(got.stats.bvh_stats);
            CHECK_FALSE(got.stats.tree_stats);
        }
    }
}

TEST_CASE("opencl bvh: doubles render the cpu device's BVH pictures, or are refused clearly", "[opencl][bvh][render]") {
    if (!have_opencl()) return;
    const Scene scene = scene_named("lens");
    CommitOptions o = bvh_options();
    o.accuracy.precision = Precision::Double;
    const Device cl = Device::open("opencl");
    if (!detail::ocl::select_device("opencl").info.fp64) {
        CHECK_THROWS_WITH(CommittedScene::commit(cl, scene, o), Catch::Contains("fp64"));
        return;
    }
    FrameOptions frame;
    frame.width = frame.height = 48;
    frame.want_ids = true;
    const RenderResult ref = CommittedScene::commit(Device::open("cpu"), scene, o).render(frame);
    const RenderResult got = CommittedScene::commit(cl, scene, o).render(frame);
    const IdMapComparison c = compare_id_maps(ref, got);
    INFO(c.summary());
    CHECK(c.unexplained == 0);
    CHECK(c.mismatches <= ref.ids.size() / 100);
    CHECK(image_rmse(ref.image, got.image) < 4e-3);
    CHECK(got.stats.opencl.kernel_options.find("-DKDRT_DOUBLE") != std::string::npos);
}

TEST_CASE("opencl bvh: a cpu and an OpenCL device share one BVH, and follow a refit", "[opencl][bvh][tiles]") {
    if (!have_opencl()) return;
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("opencl")};
    MultiDeviceScene scenes = MultiDeviceScene::commit(devices, sheet(24, 0.05), bvh_options());
    std::uint64_t builds = 0;
    for (const CommittedScene& s : scenes.scenes()) builds += s.stats().builds;
    CHECK(builds == 1);
    FrameOptions frame;
    frame.want_ids = true;
    for (double wave : {0.05, 0.15}) {
        INFO("wave " << wave);
        const Scene moved = sheet(24, wave);
        if (wave != 0.05) scenes.update(moved);
        const RenderResult tiled = scenes.render(frame, {8, 8});
        const RenderResult alone = CommittedScene::commit(devices[0], moved, bvh_options()).render(frame);
        const IdMapComparison c = compare_id_maps(alone, tiled);
        INFO(c.summary());
        CHECK(c.unexplained == 0);
        CHECK(c.mismatches <= alone.ids.size() / 100);
        CHECK(image_rmse(alone.image, tiled.image) < 4e-3);
        CHECK(tiled.stats.device_shares.size() == 2);
    }
    std::uint64_t refits = 0;
    for (const CommittedScene& s : scenes.scenes()) refits += s.stats().refits;
    CHECK(refits >= 1);
}

TEST_CASE("opencl bvh: only the stack traversal and none, and the stack reported", "[opencl][bvh]") {
    if (!have_opencl()) return;
    const Device cl = Device::open("opencl");
    const Scene scene = scene_named("2x2x4");
    for (Traversal t : {Traversal::Restart, Traversal::Ropes, Traversal::ShortStack}) {
        CommitOptions o = bvh_options();
        o.traversal = t;
        CHECK_THROWS_WITH(CommittedScene::commit(cl, scene, o), Catch::Contains("BVH") && Catch::Contains(to_string(t)));
    }
    FrameOptions frame;
    frame.width = frame.height = 16;
    std::map<Precision, std::uint64_t> bytes;
    for (Precision p : {Precision::Float, Precision::Double}) {
        if (p == Precision::Double && !detail::ocl::select_device("opencl").info.fp64) continue;
        CommitOptions o = bvh_options();
        o.accuracy.precision = p;
        const RenderResult r = CommittedScene::commit(cl, scene, o).render(frame);
        bytes[p] = r.stats.opencl.traversal_stack_bytes;
        CHECK(bytes[p] > 0);
    }
    if (bytes.count(Precision::Double) && detail::ocl::select_device("opencl").info.type == "cpu")
        CHECK(bytes[Precision::Double] > bytes[Precision::Float]);
    CommitOptions none = bvh_options();
    none.traversal = Traversal::None;
    const RenderResult r = CommittedScene::commit(cl, scene, none).render(frame);
    CHECK(r.stats.opencl.kernel_options.find("-DKDRT_TRAVERSAL=0") != std::string::npos);
    CHECK(r.stats.opencl.traversal_stack_bytes == 0);
}
