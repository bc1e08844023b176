// The OpenCL renderer against the C++ reference, on PoCL in CI: id maps and
// images of the five scenes for every traversal and schedule, specialised
// against generic kernels, the shared-structure layout, the kernel cache, and
// the errors a user can run into. Skips with a warning without OpenCL.
#include "device/kernel_records.h"
#include "have_opencl.h"
#include "opencl/cl_devices.h"
#include "opencl/cl_error.h"
#include "opencl/embedded_cl.h"
#include "opencl/kernel_variant.h"
#include "opencl/program_cache.h"

#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <map>

using namespace kdrt;

namespace {

using kdrt_test::have_opencl;

Scene scene_named(const std::string& name) { return load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json"); }

// The reference renders are shared between sections: one per scene and size.
const RenderResult& reference(const std::string& name, int size) {
    static std::map<std::pair<std::string, int>, RenderResult> cache;
    auto key = std::make_pair(name, size);
    auto it = cache.find(key);
    if (it == cache.end()) {
        RenderOptions o;
        o.device = "cpu";
        o.frame.width = o.frame.height = size;
        o.frame.want_ids = true;
        o.commit.accel = Accel::KdTree;
        it = cache.emplace(key, render(scene_named(name), o)).first;
    }
    return it->second;
}

}  // namespace

// CI sets KDRT_REQUIRE_OPENCL=1: there, a missing OpenCL platform must fail
// the run instead of letting every device test skip with a warning.
TEST_CASE("opencl: a device is present where one is required", "[opencl]") {
    const char* required = std::getenv("KDRT_REQUIRE_OPENCL");
    if (required && std::string(required) == "1") CHECK_FALSE(detail::ocl::enumerate_devices().empty());
}

TEST_CASE("opencl: shared structures have the same layout on host and device", "[opencl][render]") {
    if (!have_opencl()) return;
    const auto dev = detail::ocl::select_device("opencl");
    cl::Context ctx(dev.device);
    detail::ocl::ProgramCache cache(kdrt_test::no_disk_kernel_cache());
    // With fp64 the double-precision records are checked too.
    auto built = cache.build(ctx, dev, detail::ocl::assemble_kernel_source(), dev.info.fp64 ? "-DKDRT_DOUBLE" : "");
    cl::Kernel k(built.program, "report_layout");
    cl::Buffer out(ctx, CL_MEM_WRITE_ONLY, 64 * sizeof(cl_uint));
    k.setArg(0, out);
    cl::CommandQueue q(ctx, dev.device);
    q.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(1), cl::NDRange(1));
    std::vector<cl_uint> v(64);
    q.enqueueReadBuffer(out, CL_TRUE, 0, 64 * sizeof(cl_uint), v.data());
    std::vector<std::pair<std::size_t, std::size_t>> host = {
        {sizeof(KdNode), offsetof(KdNode, word1)},
        {sizeof(KdLeafRopes), offsetof(KdLeafRopes, box_min)},
        {sizeof(detail::GpuSphere), offsetof(detail::GpuSphere, material)},
        {sizeof(detail::GpuTriangle), offsetof(detail::GpuTriangle, zero)},
        {sizeof(detail::GpuMaterial), offsetof(detail::GpuMaterial, ior)},
        {sizeof(detail::GpuLight), offsetof(detail::GpuLight, color)},
        {sizeof(detail::GpuRay), offsetof(detail::GpuRay, pixel)},
        {sizeof(detail::GpuCamera), offsetof(detail::GpuCamera, up)},
        {sizeof(detail::GpuSceneInfo), offsetof(detail::GpuSceneInfo, box_max)},
        {sizeof(QueryRay), offsetof(QueryRay, t_max)},
        {sizeof(QueryHit), offsetof(QueryHit, kind)},
        {sizeof(detail::GpuPackedLeaf), offsetof(detail::GpuPackedLeaf, sphere_count)},
        {sizeof(detail::GpuLeafBlock), offsetof(detail::GpuLeafBlock, lanes)},
        {sizeof(detail::GpuBvhNode), offsetof(detail::GpuBvhNode, count)},
        {sizeof(detail::GpuBvhSlot), offsetof(detail::GpuBvhSlot, count)},
    };
    if (dev.info.fp64) {
        host.push_back({sizeof(detail::GpuSphereD), offsetof(detail::GpuSphereD, material)});
        host.push_back({sizeof(detail::GpuTriangleD), offsetof(detail::GpuTriangleD, v2)});
        host.push_back({sizeof(detail::GpuRayD), offsetof(detail::GpuRayD, weight)});
        host.push_back({sizeof(detail::GpuCameraD), offsetof(detail::GpuCameraD, up)});
        host.push_back({sizeof(detail::GpuLightD), offsetof(detail::GpuLightD, color)});
        host.push_back({sizeof(detail::GpuLeafBlockD), offsetof(detail::GpuLeafBlockD, lanes)});
    }
    for (std::size_t i = 0; i < host.size(); ++i) {
        INFO("structure " << i);
        CHECK(v[2 * i] == host[i].first);
        CHECK(v[2 * i + 1] == host[i].second);
    }
}

// Bound: image RMSE below 4e-3 (one 8-bit step is 3.9e-3; differences come
// from float summation order and silhouette pixels of deep reflections), and
// id mismatches only at silhouettes or ties, at most 1% of the pixels.
TEST_CASE("opencl: the five scenes match the C++ reference for every traversal and schedule", "[opencl][render][slow]") {
    if (!have_opencl()) return;
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"}) {
        const Scene scene = scene_named(name);
        for (Traversal t : {Traversal::None, Traversal::Restart, Traversal::Ropes, Traversal::Stack, Traversal::ShortStack}) {
            // Brute force over 8000 spheres is slow on a CPU: a smaller image there.
            const int size = (t == Traversal::None && std::string(name) == "ball-o-calypse") ? 40 : 96;
            const RenderResult& ref = reference(name, size);
            for (Schedule s : {Schedule::Persistent, Schedule::Wavefront, Schedule::Plain}) {
                RenderOptions o;
                o.device = "opencl";
                o.frame.width = o.frame.height = size;
                o.commit.accel = Accel::KdTree;  // the BVH's: test_opencl_bvh.cpp
                o.commit.traversal = t;
                o.frame.opencl.schedule = s;
                o.frame.want_ids = true;
                o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
                const RenderResult got = render(scene, o);
                INFO(name << ", traversal " << to_string(t) << ", schedule " << to_string(s));
                const IdMapComparison c = compare_id_maps(ref, got);
                INFO(c.summary());
                CHECK(c.unexplained == 0);
                CHECK(c.mismatches <= ref.ids.size() / 100);
                CHECK(image_rmse(ref.image, got.image) < 4e-3);
                CHECK(got.stats.rays.camera == ref.stats.rays.camera);
            }
        }
    }
}

// Byte for byte: a pixel's fixed-point sum does not depend on the order its
// rays ran in, so a pixel traced twice or never (the kernel computes rows and
// tiles, render.cl's pixel_at) shows.
TEST_CASE("opencl: ray orders give the same picture", "[opencl][render]") {
    if (!have_opencl()) return;
    const Scene scene = scene_named("2x2x4");
    RenderOptions o;
    o.device = "opencl";
    o.frame.want_ids = true;
    o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    for (const auto& [w, h] : {std::pair{70, 45}, std::pair{64, 64}, std::pair{5, 19}, std::pair{1, 1}}) {
        o.frame.width = w;
        o.frame.height = h;  // most not multiples of the tile size
        o.frame.opencl.ray_order = RayOrder::Rows;
        const RenderResult rows = render(scene, o);
        for (RayOrder r : {RayOrder::Tiles, RayOrder::Morton}) {
            o.frame.opencl.ray_order = r;
            const RenderResult other = render(scene, o);
            INFO(w << "x" << h << ", " << to_string(r));
            CHECK(std::memcmp(rows.image.rgb.data(), other.image.rgb.data(), rows.image.rgb.size() * sizeof(float)) == 0);
            CHECK(rows.ids == other.ids);
        }
    }
}

TEST_CASE("opencl: specialised and generic kernels give the same image", "[opencl][render][features]") {
    if (!have_opencl()) return;
    for (const char* name : {"2x2x4", "purple-wall", "lens"}) {
        const Scene scene = scene_named(name);
        RenderOptions o;
        o.device = "opencl";
        o.frame.width = o.frame.height = 64;
        o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
        const RenderResult special = render(scene, o);
        o.commit.all_features = true;
        const RenderResult generic = render(scene, o);
        INFO(name << ": " << special.stats.opencl.kernel_options << " vs " << generic.stats.opencl.kernel_options);
        CHECK(special.stats.opencl.kernel_options != generic.stats.opencl.kernel_options);
        CHECK(image_rmse(special.image, generic.image) < 1e-5);
    }
}

TEST_CASE("opencl: a scene without glass compiles no refraction code", "[opencl][features]") {
    // The options handed to the compiler decide what code exists: without
    // KDRT_HAS_REFRACTION the refraction block is preprocessed away.
    const auto options_for = [](const Scene& s) {
        detail::KernelVariant v;
        v.features = SceneFeatures::of(s, s.settings.max_depth);
        return detail::kernel_options(v);
    };
    const auto of = [&](const char* name) { return options_for(scene_named(name)); };
    CHECK(of("lens").find("-DKDRT_HAS_REFRACTION") != std::string::npos);
    CHECK(of("2x2x4").find("-DKDRT_HAS_REFRACTION") == std::string::npos);
    CHECK(of("2x2x4").find("-DKDRT_HAS_REFLECTION") != std::string::npos);
    // No mirrors, no glass: no bounce loop at all (depth 1), and no spheres.
    const std::string wall = of("purple-wall");
    CHECK(wall.find("-DKDRT_HAS_REFLECTION") == std::string::npos);
    CHECK(wall.find("-DKDRT_MAX_DEPTH=1") != std::string::npos);
    CHECK(wall.find("-DKDRT_HAS_SPHERES") == std::string::npos);
    // And the source really guards the code with those macros.
    const std::string src = detail::ocl::assemble_kernel_source();
    CHECK(src.find("#ifdef KDRT_HAS_REFRACTION") != std::string::npos);
    CHECK(src.find("#if KDRT_MAX_DEPTH > 1") != std::string::npos);
    // A scene without lights traces no shadow rays.
    Scene dark = scene_named("2x2x4");
    dark.lights.clear();
    CHECK(options_for(dark).find("KDRT_HAS_LIGHTS") == std::string::npos);
}

TEST_CASE("opencl: the second render of a scene does not compile", "[opencl][cache]") {
    if (!have_opencl()) return;
    const auto dir = std::filesystem::temp_directory_path() / "kdrt-test-render-cache";
    std::filesystem::remove_all(dir);
    RenderOptions o;
    o.device = "opencl";
    o.frame.width = o.frame.height = 16;
    o.commit.kernel_cache_dir = dir;
    const Scene scene = scene_named("lens");
    CHECK_FALSE(render(scene, o).stats.opencl.kernel_cache_hit);
    CHECK(render(scene, o).stats.opencl.kernel_cache_hit);
    std::filesystem::remove_all(dir);
}

TEST_CASE("opencl: bad device names and oversize buffers give clear errors", "[opencl][errors]") {
    if (!have_opencl()) return;
    const Scene scene = scene_named("lens");
    RenderOptions o;
    o.frame.width = o.frame.height = 8;
    for (const char* bad : {"opencl:99", "opencl:no-such-device", "cuda", "gpu0"}) {
        o.device = bad;
        INFO(bad);
        try {
            render(scene, o);
            FAIL("no error for device " << bad);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            CHECK(std::string(e.what()).find(bad) != std::string::npos);
        }
    }
    // 16384 x 16384 RGB floats (3 GiB) exceed PoCL's largest allocation: refused before any work.
    const auto dev = detail::ocl::select_device("opencl");
    if (dev.info.max_allocation < 16384ull * 16384ull * 12ull) {
        o.device = "opencl";
        o.frame.width = o.frame.height = 16384;
        o.commit.traversal = Traversal::None;
        o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
        try {
            render(scene, o);
            FAIL("no error for an oversize image");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            CHECK(std::string(e.what()).find("largest allocation") != std::string::npos);
        }
    }
}

// Kernel resources: every kernel of the program is reported with what the
// implementation says it allows, and kdrt's stack estimate orders the
// traversals as their arrays do (ropes and restart keep none, the short stack
// a few entries, the full stack one per tree level; doubles make them bigger).
TEST_CASE("opencl: a render reports its kernels' resources and the traversal stack", "[opencl][render]") {
    if (!have_opencl()) return;
    const Scene scene = scene_named("2x2x4");
    std::map<std::pair<Traversal, Precision>, std::uint64_t> stack_bytes;
    for (Traversal t : {Traversal::Restart, Traversal::Ropes, Traversal::Stack, Traversal::ShortStack})
        for (Precision p : {Precision::Float, Precision::Double}) {
            if (p == Precision::Double && !detail::ocl::select_device("opencl").info.fp64) continue;
            RenderOptions o;
            o.device = "opencl";
            o.frame.width = o.frame.height = 16;
            o.commit.accel = Accel::KdTree;  // the BVH's: test_opencl_bvh.cpp
            o.commit.traversal = t;
            o.commit.accuracy.precision = p;
            o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
            const RenderResult r = render(scene, o);
            INFO("traversal " << to_string(t) << ", precision " << to_string(p));
            std::vector<std::string> names;
            for (const KernelResources& k : r.stats.opencl.kernel_resources) {
                INFO("kernel " << k.kernel);
                names.push_back(k.kernel);
                CHECK(k.work_group_size >= 1);
                CHECK(k.preferred_multiple >= 1);
                CHECK(k.preferred_multiple <= k.work_group_size);
            }
            // The renderer's kernels and the ray queries' are all in the one program, each once, sorted.
            for (const char* k : {"trace_persistent", "trace_plain", "query_closest", "query_any"})
                CHECK(std::count(names.begin(), names.end(), k) == 1);
            CHECK(std::is_sorted(names.begin(), names.end()));
            stack_bytes[{t, p}] = r.stats.opencl.traversal_stack_bytes;
        }
    for (Precision p : {Precision::Float, Precision::Double}) {
        if (!stack_bytes.count({Traversal::Stack, p})) continue;
        CHECK(stack_bytes[{Traversal::Restart, p}] == 0);
        CHECK(stack_bytes[{Traversal::Ropes, p}] == 0);
        CHECK(stack_bytes[{Traversal::ShortStack, p}] > 0);
        CHECK(stack_bytes[{Traversal::ShortStack, p}] * 8 < stack_bytes[{Traversal::Stack, p}]);
    }
    if (stack_bytes.count({Traversal::Stack, Precision::Double}))
        CHECK(stack_bytes[{Traversal::Stack, Precision::Double}] > stack_bytes[{Traversal::Stack, Precision::Float}]);
}
