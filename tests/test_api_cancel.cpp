// Cancelling through FrameOptions::progress and CommitOptions::progress: a long cpu render and a long
// kd-tree or BVH build stop with kdrt::Error(Cancelled) when the callback returns
// false (here on a request from another thread); a callback that throws
// stops them with its own exception.
#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/render.h>

#include <catch2/catch.hpp>

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

using namespace kdrt;

namespace {

// A wavy heightfield of 2 n^2 triangles under a light: slow to build and to render.
Scene big_mesh_scene(int n) {
    Scene s;
    s.camera.position = {0, 3, -3};
    s.camera.look_at = {0, 0, 0};
    auto m = s.add_material({});
    s.add_light({{2, 5, -2}, {1, 1, 1}});
    Mesh mesh;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            const double u = 2.0 * x / n - 1.0, v = 2.0 * y / n - 1.0;
            mesh.positions.push_back({u, 0.1 * std::sin(9 * u) * std::cos(7 * v), v});
        }
    const auto row = static_cast<std::uint32_t>(n + 1);
    for (std::uint32_t y = 0; y < static_cast<std::uint32_t>(n); ++y)
        for (std::uint32_t x = 0; x < static_cast<std::uint32_t>(n); ++x) {
            const std::uint32_t a = y * row + x;
            mesh.triangles.push_back({{a, a + 1, a + row + 1}, {kNoNormal, kNoNormal, kNoNormal}, m});
            mesh.triangles.push_back({{a, a + row + 1, a + row}, {kNoNormal, kNoNormal, kNoNormal}, m});
        }
    s.add_mesh(std::move(mesh));
    return s;
}

// Another thread asks for cancellation once the callback has been called;
// the callback then returns false. Records the largest fraction it saw.
struct CancelFromAnotherThread {
    std::atomic<bool> called{false}, cancel{false};
    std::atomic<double> largest{0.0};
    std::thread canceller{[this] {
        while (!called.load()) std::this_thread::yield();
        cancel.store(true);
    }};

    std::function<bool(double)> callback() {
        return [this](double f) {
            if (f > largest.load()) largest.store(f);
            called.store(true);
            return !cancel.load();
        };
    }
    ~CancelFromAnotherThread() {
        called.store(true);
        canceller.join();
    }
};

ErrorCode code_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.code();
    }
    FAIL("no kdrt::Error");
    return ErrorCode::InvalidArgument;
}

}  // namespace

TEST_CASE("api: a long cpu render is cancelled through progress", "[api][cancel]") {
    const Scene scene = big_mesh_scene(60);
    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), scene, {});
    CancelFromAnotherThread cancel;
    FrameOptions frame;
    frame.width = 4096;
    frame.height = 4096;
    frame.samples = 16;
    frame.progress = cancel.callback();
    CHECK(code_of([&] { (void)c.render(frame); }) == ErrorCode::Cancelled);
    CHECK(cancel.largest.load() < 1.0);
}

TEST_CASE("api: a long kd-tree or BVH build is cancelled through progress", "[api][cancel]") {
    const Scene scene = big_mesh_scene(400);
    for (const Accel accel : {Accel::KdTree, Accel::Bvh}) {
        CAPTURE(to_string(accel));
        CancelFromAnotherThread cancel;
        CommitOptions o;
        o.accel = accel;
        o.progress = cancel.callback();
        CHECK(code_of([&] { (void)CommittedScene::commit(Device::open("cpu"), scene, o); }) == ErrorCode::Cancelled);
        CHECK(cancel.largest.load() < 1.0);
    }
}

TEST_CASE("api: a throwing progress callback stops a render and a build with its exception", "[api][cancel]") {
    CommitOptions o;
    o.progress = [](double) -> bool { throw std::runtime_error("stop here"); };
    const Scene small = big_mesh_scene(40);
    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), small, {});
    FrameOptions frame;
    frame.width = frame.height = 1024;
    frame.progress = o.progress;
    CHECK_THROWS_WITH(c.render(frame), "stop here");
    CHECK_THROWS_WITH(CommittedScene::commit(Device::open("cpu"), big_mesh_scene(200), o), "stop here");
}
