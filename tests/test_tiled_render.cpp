// Frames in pieces ([tiles]): FrameOptions::region renders exactly the
// whole frame's pixels on every device (byte for byte: image, ids, hit_t),
// and bad regions are rejected.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>
#include <kdrt/tiled_render.h>

#include <catch2/catch.hpp>

#include "have_opencl.h"
#include "render/committed_scene_state.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <stdexcept>
#include <tuple>
#include <vector>

using namespace kdrt;

namespace {

Scene scene_named(const std::string& name) { return load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json"); }

// The one-call render's options for `frame` (the commit's default).
RenderOptions one_call(const FrameOptions& frame) {
    RenderOptions o;
    o.frame = frame;
    return o;
}

bool has_opencl_device() {
    for (const DeviceInfo& d : list_devices())
        if (d.id != "cpu") return true;
    return false;
}

// The frame's pixels of `r` as a region-sized result's would be laid out.
template <class T>
std::vector<T> crop(const std::vector<T>& frame, int frame_width, const PixelRect& r, int channels) {
    std::vector<T> out;
    out.reserve(static_cast<std::size_t>(r.width) * r.height * channels);
    for (int y = r.y; y < r.y + r.height; ++y) {
        const auto row = frame.begin() + (static_cast<std::ptrdiff_t>(y) * frame_width + r.x) * channels;
        out.insert(out.end(), row, row + static_cast<std::ptrdiff_t>(r.width) * channels);
    }
    return out;
}

// Byte equality (float == would call -0 and 0 equal and NaN unequal).
template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Odd regions of a W x H frame: single pixels at the corners, the last row and
// column, one middle row, an interior block, the bottom-right corner block,
// and the whole frame.
std::vector<PixelRect> odd_regions(int W, int H) {
    return {{0, 0, 1, 1},          {W - 1, H - 1, 1, 1},  {W - 1, 0, 1, H},        {0, H - 1, W, 1},
            {0, H / 2, W, 1},      {13, 7, 29, 17},       {W - 20, H - 11, 20, 11}, {0, 0, W, H}};
}

// Renders the whole frame and each odd region of it on one committed scene and
// checks every region against the frame's pixels.
void check_regions(const CommittedScene& committed, FrameOptions frame, const std::string& what) {
    frame.want_ids = true;
    frame.region.reset();
    const RenderResult full = committed.render(frame);
    const int W = full.image.width, H = full.image.height;
    for (const PixelRect& r : odd_regions(W, H)) {
        frame.region = r;
        const RenderResult part = committed.render(frame);
        INFO(what << ", region x " << r.x << " y " << r.y << " " << r.width << "x" << r.height);
        REQUIRE(part.image.width == r.width);
        REQUIRE(part.image.height == r.height);
        CHECK(same_bytes(part.image.rgb, crop(full.image.rgb, W, r, 3)));
        CHECK(same_bytes(part.ids, crop(full.ids, W, r, 1)));
        CHECK(same_bytes(part.hit_t, crop(full.hit_t, W, r, 1)));
        CHECK(part.stats.rays.camera == static_cast<std::uint64_t>(r.width) * r.height * full.stats.rays.camera / (W * H));
    }
}

struct Config {
    const char* scene;
    Accel accel;
    Traversal traversal;
    int samples;
};

// lens has glass (two secondary rays per hit), purple-wall mirrors, 2x2x4
// triangles; two configurations take two samples per pixel.
const Config kConfigs[] = {{"lens", Accel::KdTree, Traversal::Stack, 1},
                           {"purple-wall", Accel::KdTree, Traversal::Ropes, 1},
                           {"2x2x4", Accel::KdTree, Traversal::ShortStack, 1},
                           {"lens", Accel::KdTree, Traversal::Restart, 2},
                           {"purple-wall", Accel::Bvh, Traversal::Stack, 1},
                           {"lens", Accel::Bvh, Traversal::Stack, 2}};

void check_device(const std::string& device_name, Precision precision) {
    const Device device = Device::open(device_name);
    for (const Config& c : kConfigs) {
        CommitOptions o;
        o.accel = c.accel;
        o.traversal = c.traversal;
        o.accuracy.precision = precision;
        o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
        const CommittedScene committed = CommittedScene::commit(device, scene_named(c.scene), o);
        FrameOptions frame;
        frame.width = 96;
        frame.height = 72;
        frame.samples = c.samples;
        check_regions(committed, frame,
                      device_name + " " + to_string(precision) + ", " + c.scene + ", " + to_string(c.accel) + " " +
                          to_string(c.traversal) +
                          ", " + std::to_string(c.samples) + " samples");
    }
}

}  // namespace

TEST_CASE("tiles: a region of a cpu render equals the whole frame's pixels", "[tiles]") {
    check_device("cpu", Precision::Float);
    check_device("cpu", Precision::Double);
}

TEST_CASE("tiles: a region of an OpenCL render equals the whole frame's pixels", "[tiles][opencl]") {
    if (!has_opencl_device()) {
        WARN("no OpenCL device: skipping");
        return;
    }
    check_device("opencl", Precision::Float);
    if (Device::open("opencl").info().fp64) check_device("opencl", Precision::Double);
}

TEST_CASE("tiles: an OpenCL region is the same whatever the ray order and schedule", "[tiles][opencl]") {
    if (!has_opencl_device()) {
        WARN("no OpenCL device: skipping");
        return;
    }
    const Device device = Device::open("opencl");
    CommitOptions o;
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    const CommittedScene committed = CommittedScene::commit(device, scene_named("lens"), o);
    std::vector<float> first;
    for (RayOrder order : {RayOrder::Rows, RayOrder::Tiles, RayOrder::Morton})
        for (Schedule schedule : {Schedule::Plain, Schedule::Persistent, Schedule::Wavefront}) {
            FrameOptions frame;
            frame.width = 80;
            frame.height = 60;
            frame.opencl.ray_order = order;
            frame.opencl.schedule = schedule;
            const std::string what = std::string(to_string(order)) + ", " + to_string(schedule);
            check_regions(committed, frame, what);
            // The whole frame too is the same in any order (fixed-point sums).
            const RenderResult full = committed.render(frame);
            if (first.empty()) first = full.image.rgb;
            INFO(what);
            CHECK(same_bytes(full.image.rgb, first));
        }
    // Short launches split a bounce's queue differently: the old float sums
    // differed here at 640x480 (Morton, 1 ms launches).
    FrameOptions frame;
    frame.width = 320;
    frame.height = 240;
    frame.opencl.ray_order = RayOrder::Rows;
    const RenderResult rows = committed.render(frame);
    frame.opencl.ray_order = RayOrder::Morton;
    frame.opencl.max_launch_ms = 1.0;
    CHECK(same_bytes(committed.render(frame).image.rgb, rows.image.rgb));
}

TEST_CASE("tiles: an OpenCL scene's frames reuse its buffers and equal a fresh commit's", "[tiles][opencl]") {
    if (!has_opencl_device()) {
        WARN("no OpenCL device: skipping");
        return;
    }
    // A committed scene keeps its frame buffers (image, id map, queues, pixel
    // table) for the next frame that fits (cl_frame_renderer.h, FrameBuffers):
    // frames of other sizes, orders, samples and with or without ids, one
    // after another, must each be what a scene committed for it alone gives.
    const Device device = Device::open("opencl");
    CommitOptions o;
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    const Scene scene = scene_named("lens");
    const CommittedScene kept = CommittedScene::commit(device, scene, o);
    struct Frame {
        int width, height, samples;
        RayOrder order;
        bool ids;
        std::optional<PixelRect> region;
    };
    const Frame frames[] = {{80, 60, 1, RayOrder::Tiles, true, std::nullopt},
                            {30, 20, 1, RayOrder::Morton, false, std::nullopt},
                            {80, 60, 1, RayOrder::Rows, true, std::nullopt},
                            {120, 90, 2, RayOrder::Morton, true, std::nullopt},
                            {120, 90, 1, RayOrder::Morton, true, PixelRect{7, 5, 33, 21}},
                            {80, 60, 1, RayOrder::Tiles, true, std::nullopt}};
    for (const Frame& f : frames) {
        FrameOptions frame;
        frame.width = f.width;
        frame.height = f.height;
        frame.samples = f.samples;
        frame.opencl.ray_order = f.order;
        frame.want_ids = f.ids;
        frame.region = f.region;
        INFO(f.width << "x" << f.height << ", " << f.samples << " samples, " << to_string(f.order));
        const RenderResult again = kept.render(frame);
        const RenderResult fresh = CommittedScene::commit(device, scene, o).render(frame);
        CHECK(same_bytes(again.image.rgb, fresh.image.rgb));
        CHECK(same_bytes(again.ids, fresh.ids));
        CHECK(same_bytes(again.hit_t, fresh.hit_t));
    }
}

TEST_CASE("tiles: a region outside the frame or empty is rejected", "[tiles]") {
    const Device cpu = Device::open("cpu");
    const CommittedScene committed = CommittedScene::commit(cpu, scene_named("2x2x4"), {});
    const PixelRect bad[] = {{0, 0, 0, 5},   {0, 0, 5, -1},      {-1, 0, 4, 4},      {0, -3, 4, 4},
                             {90, 0, 7, 4},  {0, 70, 4, 3},      {INT_MAX, 0, 1, 1}, {1, 1, INT_MAX, 1}};
    for (const PixelRect& r : bad) {
        FrameOptions frame;
        frame.width = 96;
        frame.height = 72;
        frame.region = r;
        INFO("region x " << r.x << " y " << r.y << " " << r.width << "x" << r.height);
        try {
            (void)committed.render(frame);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(std::string(e.what()).find("region") != std::string::npos);
        }
    }
    // The one-call render checks it too.
    RenderOptions o;
    o.frame.width = 10;
    o.frame.height = 10;
    o.frame.region = PixelRect{5, 5, 6, 1};
    CHECK_THROWS_AS(render(scene_named("2x2x4"), o), Error);
}

// ---- several devices: kdrt/tiled_render.h --------------------------------

namespace {

const char* const kStudyScenes[] = {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"};

// Two handles to one device kind: the tiles they share must give exactly the
// picture the device renders alone.
void check_same_kind(const std::string& device_name, int width, int height, TileSize tile) {
    const std::vector<Device> devices = {Device::open(device_name), Device::open(device_name)};
    CommitOptions o;
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    for (const char* name : kStudyScenes) {
        const Scene scene = scene_named(name);
        const CommittedScene alone = CommittedScene::commit(devices[0], scene, o);
        const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene, o);
        FrameOptions frame;
        frame.width = width;
        frame.height = height;
        frame.want_ids = true;
        const RenderResult one = alone.render(frame);
        const RenderResult both = multi.render(frame, tile);
        INFO(device_name << " x2, " << name);
        CHECK(same_bytes(both.image.rgb, one.image.rgb));
        CHECK(same_bytes(both.ids, one.ids));
        CHECK(same_bytes(both.hit_t, one.hit_t));
        CHECK(both.stats.rays.total() == one.stats.rays.total());
        // The tree was built once and handed to the second device.
        CHECK(multi.scenes()[0].stats().builds == 1);
        CHECK(multi.scenes()[1].stats().builds == 0);
        // The shares add up to the frame.
        REQUIRE(both.stats.device_shares.size() == 2);
        std::uint64_t tiles = 0, pixels = 0;
        RayCounts rays;
        for (const DeviceShare& s : both.stats.device_shares) {
            tiles += s.tiles;
            pixels += s.pixels;
            rays += s.rays;
            CHECK(s.busy_ms >= 0.0);
            CHECK_FALSE(s.device_name.empty());
        }
        CHECK(tiles == cut_into_tiles(width, height, tile).size());
        CHECK(pixels == static_cast<std::uint64_t>(width) * height);
        CHECK(rays.total() == both.stats.rays.total());
        CHECK(rays.camera == both.stats.rays.camera);
    }
}

}  // namespace

TEST_CASE("tiles: cut_into_tiles covers the frame once, clipping at the edges", "[tiles]") {
    for (const auto& [W, H, tile] : {std::tuple{96, 72, TileSize{64, 64}}, std::tuple{1, 1, TileSize{64, 64}},
                                     std::tuple{100, 37, TileSize{16, 8}}, std::tuple{5, 300, TileSize{1, 1}},
                                     std::tuple{20, 20, TileSize{INT_MAX, INT_MAX}}}) {
        const std::vector<PixelRect> tiles = cut_into_tiles(W, H, tile);
        std::vector<int> covered(static_cast<std::size_t>(W) * H, 0);
        int last_y = 0;
        for (const PixelRect& t : tiles) {
            REQUIRE(t.width > 0);
            REQUIRE(t.height > 0);
            REQUIRE(t.width <= tile.width);
            REQUIRE(t.height <= tile.height);
            REQUIRE(t.x + t.width <= W);
            REQUIRE(t.y + t.height <= H);
            CHECK(t.y >= last_y);  // rows of tiles from the top
            last_y = t.y;
            for (int y = t.y; y < t.y + t.height; ++y)
                for (int x = t.x; x < t.x + t.width; ++x) ++covered[static_cast<std::size_t>(y) * W + x];
        }
        CHECK(std::count(covered.begin(), covered.end(), 1) == W * H);
    }
    CHECK_THROWS_AS(cut_into_tiles(0, 10), Error);
    CHECK_THROWS_AS(cut_into_tiles(10, 10, {0, 4}), Error);
    CHECK_THROWS_AS(cut_into_tiles(10, 10, {4, -1}), Error);
}

TEST_CASE("tiles: open_devices opens a list, all, and names bad lists", "[tiles]") {
    const std::vector<Device> one = open_devices("cpu");
    REQUIRE(one.size() == 1);
    CHECK(one[0].info().id == "cpu");
    const std::vector<Device> all = open_devices("all");
    REQUIRE(all.size() == list_devices().size());
    CHECK(all[0].info().id == "cpu");
    for (const char* bad : {"", ",", "cpu,", "cpu,,cpu", "cpu,cpu", "all,cpu", "nonsense", "cpu,nonsense"}) {
        INFO("list '" << bad << "'");
        try {
            (void)open_devices(bad);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            const std::string what = e.what();
            CHECK(what.find(std::string(bad) == "cpu,nonsense" ? "nonsense" : bad) != std::string::npos);
        }
    }
    if (has_opencl_device()) {
        CHECK(open_devices("cpu, opencl").size() == 2);
        CHECK_THROWS_AS(open_devices("opencl,opencl:0"), Error);  // one device, two names
    }
}

TEST_CASE("tiles: two cpu devices give the single-device picture", "[tiles][parallel]") {
    check_same_kind("cpu", 64, 48, {16, 16});
}

TEST_CASE("tiles: two handles to one OpenCL device give the single-device picture", "[tiles][opencl]") {
    if (!has_opencl_device()) {
        WARN("no OpenCL device: skipping");
        return;
    }
    check_same_kind("opencl", 64, 48, {32, 16});
}

TEST_CASE("tiles: cpu and OpenCL tiles are each what their device renders alone", "[tiles][opencl]") {
    if (!has_opencl_device()) {
        WARN("no OpenCL device: skipping");
        return;
    }
    const std::vector<Device> devices = open_devices("cpu,opencl");
    CommitOptions o;
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    for (const char* name : {"lens", "purple-wall"}) {
        const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene_named(name), o);
        FrameOptions frame;
        frame.width = 72;
        frame.height = 56;
        frame.want_ids = true;
        const std::vector<PixelRect> tiles = cut_into_tiles(frame.width, frame.height, {16, 16});
        std::size_t next = 0;
        std::vector<std::pair<std::size_t, PixelRect>> taken;
        std::vector<RenderResult> results;
        const std::vector<DeviceShare> shares = render_tiles(
            multi.scenes(), frame,
            [&]() -> std::optional<PixelRect> {
                if (next == tiles.size()) return std::nullopt;
                return tiles[next++];
            },
            [&](std::size_t device, const PixelRect& tile, RenderResult&& r) {
                taken.emplace_back(device, tile);
                results.push_back(std::move(r));
            });
        REQUIRE(taken.size() == tiles.size());
        std::uint64_t tile_count = 0;
        for (const DeviceShare& s : shares) tile_count += s.tiles;
        CHECK(tile_count == tiles.size());
        for (std::size_t i = 0; i < taken.size(); ++i) {
            const auto& [device, tile] = taken[i];
            FrameOptions alone = frame;
            alone.region = tile;
            const RenderResult expected = multi.scenes()[device].render(alone);
            INFO(name << ", device " << device << ", tile x " << tile.x << " y " << tile.y);
            CHECK(same_bytes(results[i].image.rgb, expected.image.rgb));
            CHECK(same_bytes(results[i].ids, expected.ids));
        }
        // The assembled frame has the shares and the frame's size.
        const RenderResult r = multi.render(frame, {16, 16});
        CHECK(r.image.width == frame.width);
        CHECK(r.stats.device_shares.size() == 2);
        std::uint64_t pixels = 0;
        for (const DeviceShare& s : r.stats.device_shares) pixels += s.pixels;
        CHECK(pixels == static_cast<std::uint64_t>(frame.width) * frame.height);
    }
}

TEST_CASE("tiles: a failing callback stops every device and its exception comes out", "[tiles][parallel]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu"), Device::open("cpu")};
    const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene_named("purple-wall"), {});
    FrameOptions frame;
    frame.width = 64;
    frame.height = 48;
    const std::vector<PixelRect> tiles = cut_into_tiles(frame.width, frame.height, {8, 8});
    for (const char* where : {"tile_done", "next_tile"}) {
        INFO(where);
        std::size_t next = 0, done = 0, calls_after_throw = 0;
        bool thrown = false;
        try {
            (void)render_tiles(
                multi.scenes(), frame,
                [&]() -> std::optional<PixelRect> {
                    if (thrown) ++calls_after_throw;
                    if (std::string(where) == "next_tile" && next == 5) {
                        thrown = true;
                        throw std::runtime_error("next_tile failed");
                    }
                    if (next == tiles.size()) return std::nullopt;
                    return tiles[next++];
                },
                [&](std::size_t, const PixelRect&, RenderResult&&) {
                    if (thrown) ++calls_after_throw;
                    if (std::string(where) == "tile_done" && ++done == 3) {
                        thrown = true;
                        throw std::runtime_error("tile_done failed");
                    }
                });
            FAIL("no exception");
        } catch (const std::runtime_error& e) {
            CHECK(std::string(e.what()) == std::string(where) + " failed");
        }
        CHECK(calls_after_throw == 0);
        CHECK(next < tiles.size());
    }
    // A render error on one device (a region outside the frame) comes out too.
    std::size_t handed = 0;
    CHECK_THROWS_AS(render_tiles(
                        multi.scenes(), frame,
                        [&]() -> std::optional<PixelRect> {
                            if (handed++ > 20) return std::nullopt;
                            return handed == 4 ? PixelRect{60, 0, 8, 8} : PixelRect{0, 0, 8, 8};
                        },
                        [](std::size_t, const PixelRect&, RenderResult&&) {}),
                    Error);
}

TEST_CASE("tiles: progress runs to the whole frame and false cancels", "[tiles][parallel]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu")};
    const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene_named("lens"), {});
    FrameOptions frame;
    frame.width = 64;
    frame.height = 48;
    std::vector<double> seen;
    frame.progress = [&](double f) {
        seen.push_back(f);
        return true;
    };
    (void)multi.render(frame, {16, 16});
    REQUIRE_FALSE(seen.empty());
    CHECK(seen.back() == 1.0);
    CHECK(std::all_of(seen.begin(), seen.end(), [](double f) { return f >= 0.0 && f <= 1.0; }));
    int calls = 0;
    frame.progress = [&](double) { return ++calls < 3; };
    try {
        (void)multi.render(frame, {8, 8});
        FAIL("not cancelled");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Cancelled);
    }
}

TEST_CASE("tiles: updates keep the devices in step and build a new geometry once", "[tiles]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu")};
    Scene scene = scene_named("purple-wall");
    MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene, {});
    FrameOptions frame;
    frame.width = 48;
    frame.height = 32;
    // Camera moved: shading only, no build.
    scene.camera.position += glm::dvec3(0.3, 0.2, 0.0);
    multi.update(scene);
    CHECK(same_bytes(multi.render(frame, {16, 16}).image.rgb, render(scene, one_call(frame)).image.rgb));
    CHECK(multi.scenes()[0].stats().builds + multi.scenes()[1].stats().builds == 1);
    // New geometry: one build, shared.
    scene.add_sphere(scene.camera.look_at, 0.5, scene.add_material({}));
    multi.update(scene);
    const RenderResult r = multi.render(frame, {16, 16});
    CHECK(r.stats.builds == 1);
    CHECK(multi.scenes()[0].stats().builds + multi.scenes()[1].stats().builds == 2);
    CHECK(same_bytes(r.image.rgb, render(scene, one_call(frame)).image.rgb));
}

// A frame of one tile leaves one device without a tile: the work of the
// commit is still reported with that frame, whichever device took the tile
// (it was once carried to the next frame the idle device took part in).
// After the frame no device may hold work to report.
TEST_CASE("tiles: a device that gets no tile reports its work with the frame", "[tiles]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu")};
    const Scene scene = scene_named("purple-wall");
    FrameOptions frame;
    frame.width = 16;
    frame.height = 16;
    for (int round = 0; round < 8; ++round) {
        const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene, {});
        const RenderResult first = multi.render(frame, {16, 16});
        REQUIRE(first.stats.device_shares.size() == 2);
        CHECK(first.stats.device_shares[0].tiles + first.stats.device_shares[1].tiles == 1);
        CHECK(first.stats.builds == 1);
        for (const CommittedScene& c : multi.scenes()) {
            const detail::PendingWork& pending = detail::CommittedSceneAccess::state(c, "test").pending;
            CHECK(pending.builds == 0);
            CHECK_FALSE(pending.tree_loaded);  // the second device's tree came in memory
            CHECK(pending.warnings.empty());
        }
        CHECK(multi.render(frame, {16, 16}).stats.builds == 0);
    }
}

TEST_CASE("tiles: several devices render a region of the frame in tiles too", "[tiles]") {
    const std::vector<Device> devices = {Device::open("cpu"), Device::open("cpu")};
    const Scene scene = scene_named("lens");
    const MultiDeviceScene multi = MultiDeviceScene::commit(devices, scene, {});
    FrameOptions frame;
    frame.width = 64;
    frame.height = 48;
    frame.want_ids = true;
    const RenderResult full = render(scene, one_call(frame));
    const PixelRect region{5, 9, 37, 21};
    frame.region = region;
    const RenderResult part = multi.render(frame, {8, 8});
    REQUIRE(part.image.width == region.width);
    REQUIRE(part.image.height == region.height);
    CHECK(same_bytes(part.image.rgb, crop(full.image.rgb, 64, region, 3)));
    CHECK(same_bytes(part.ids, crop(full.ids, 64, region, 1)));
    std::uint64_t pixels = 0;
    for (const DeviceShare& s : part.stats.device_shares) pixels += s.pixels;
    CHECK(pixels == static_cast<std::uint64_t>(region.width) * region.height);
    frame.region = PixelRect{60, 0, 8, 8};
    CHECK_THROWS_AS(multi.render(frame), Error);
}
