#include "cluster/tile_loop.h"

#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <thread>

namespace kdrt::cluster {

std::vector<DeviceShare> run_tile_loop(std::size_t devices, const CommitOnDevice& commit, const Scene& scene,
                                       const FrameOptions& frame, const FrameCamera& camera, TileSource& source) {
    std::vector<DeviceShare> shares(devices);
    std::mutex source_mutex;
    std::atomic<bool> stop{false};
    std::exception_ptr first_error;

    auto device_loop = [&](std::size_t d) {
        DeviceShare& share = shares[d];
        int current_frame = 0;
        std::optional<Scene> moved;  // a copy of the scene only once a frame needs another camera
        try {
            CommittedScene committed = commit(d);
            share.device_name = committed.device().info().id;  // until a render names it
            while (!stop) {
                std::optional<TileWork> work;
                {
                    std::lock_guard lock(source_mutex);
                    work = source.next();
                }
                if (!work) break;
                if (work->frame != current_frame) {
                    if (!moved) moved = scene;
                    moved->camera = camera(scene.camera, work->frame);
                    committed.update(*moved);
                    current_frame = work->frame;
                }
                FrameOptions o = frame;
                o.region = work->rect;
                o.progress = nullptr;
                const auto start = std::chrono::steady_clock::now();
                RenderResult r = committed.render(o);
                share.busy_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
                if (share.tiles == 0) share.device_name = r.stats.device_name;
                share.tiles += 1;
                share.pixels += static_cast<std::uint64_t>(work->rect.width) * static_cast<std::uint64_t>(work->rect.height);
                share.rays += r.stats.rays;
                std::lock_guard lock(source_mutex);
                source.done(*work, std::move(r));
            }
        } catch (...) {
            std::lock_guard lock(source_mutex);
            if (!first_error) first_error = std::current_exception();
            stop = true;
        }
    };

    if (devices == 1) {
        device_loop(0);  // on the calling thread: MPI calls stay on the thread that initialised it
    } else {
        std::vector<std::thread> threads;
        for (std::size_t d = 0; d < devices; ++d) threads.emplace_back(device_loop, d);
        for (std::thread& t : threads) t.join();
    }
    if (first_error) std::rethrow_exception(first_error);
    return shares;
}

}  // namespace kdrt::cluster
