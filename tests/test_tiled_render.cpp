// Frames in pieces ([tiles]): RenderOptions::region renders exactly the
// whole frame's pixels on every device (byte for byte: image, ids, hit_t),
// and bad regions are rejected.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/device_handle.h>
#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <climits>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

Scene scene_named(const std::string& name) { return load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json"); }

bool has_opencl_device() {
    for (const DeviceInfo& d : list_devices())
        if (d.id != "cpu") return true;
    return false;
}

std::filesystem::path test_kernel_cache() { return std::filesystem::temp_directory_path() / "kdrt-test-kernel-cache"; }

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
void check_regions(const CommittedScene& committed, RenderOptions frame, const std::string& what) {
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
        CHECK(part.rays.camera == static_cast<std::uint64_t>(r.width) * r.height * full.rays.camera / (W * H));
    }
}

struct Config {
    const char* scene;
    Traversal traversal;
    int samples;
};

// lens has glass (two secondary rays per hit), purple-wall mirrors, 2x2x4
// triangles; one configuration takes two samples per pixel.
const Config kConfigs[] = {{"lens", Traversal::Stack, 1},
                           {"purple-wall", Traversal::Ropes, 1},
                           {"2x2x4", Traversal::ShortStack, 1},
                           {"lens", Traversal::Restart, 2}};

void check_device(const std::string& device_name, Precision precision) {
    const Device device = Device::open(device_name);
    for (const Config& c : kConfigs) {
        RenderOptions o;
        o.traversal = c.traversal;
        o.precision = precision;
        o.kernel_cache_dir = test_kernel_cache();
        const CommittedScene committed = CommittedScene::commit(device, scene_named(c.scene), o);
        RenderOptions frame;
        frame.width = 96;
        frame.height = 72;
        frame.samples = c.samples;
        check_regions(committed, frame,
                      device_name + " " + to_string(precision) + ", " + c.scene + ", " + to_string(c.traversal) +
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
    RenderOptions o;
    o.kernel_cache_dir = test_kernel_cache();
    const CommittedScene committed = CommittedScene::commit(device, scene_named("lens"), o);
    std::vector<float> first;
    for (RayOrder order : {RayOrder::Rows, RayOrder::Morton})
        for (Schedule schedule : {Schedule::Plain, Schedule::Persistent}) {
            RenderOptions frame;
            frame.width = 80;
            frame.height = 60;
            frame.ray_order = order;
            frame.schedule = schedule;
            const std::string what = std::string(to_string(order)) + ", " + to_string(schedule);
            check_regions(committed, frame, what);
            // The whole frame too is the same in any order (fixed-point sums).
            const RenderResult full = committed.render(frame);
            if (first.empty()) first = full.image.rgb;
            INFO(what);
            CHECK(same_bytes(full.image.rgb, first));
        }
}

TEST_CASE("tiles: a region outside the frame or empty is rejected", "[tiles]") {
    const Device cpu = Device::open("cpu");
    const CommittedScene committed = CommittedScene::commit(cpu, scene_named("2x2x4"), {});
    const PixelRect bad[] = {{0, 0, 0, 5},   {0, 0, 5, -1},      {-1, 0, 4, 4},      {0, -3, 4, 4},
                             {90, 0, 7, 4},  {0, 70, 4, 3},      {INT_MAX, 0, 1, 1}, {1, 1, INT_MAX, 1}};
    for (const PixelRect& r : bad) {
        RenderOptions frame;
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
    o.width = 10;
    o.height = 10;
    o.region = PixelRect{5, 5, 6, 1};
    CHECK_THROWS_AS(render(scene_named("2x2x4"), o), Error);
}
