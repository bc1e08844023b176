// kdrt/tiled_render.h: a frame cut into tiles that several devices pull from
// one counter, each tile rendered with RenderOptions::region (bit for bit the
// device's whole-frame pixels), and the scene committed once per device with
// one shared kd-tree.
#include "render/committed_scene_state.h"
#include "scene/prepared_scene.h"

#include <kdrt/error.h>
#include <kdrt/tiled_render.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

namespace kdrt {

namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

std::string trimmed(const std::string& s) {
    const auto first = s.find_first_not_of(" \t");
    if (first == std::string::npos) return {};
    return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

std::string describe_device(const Device& d) { return d.info().id + " (" + d.info().name + ")"; }

}  // namespace

std::vector<PixelRect> cut_into_tiles(int frame_width, int frame_height, TileSize tile) {
    if (frame_width <= 0 || frame_height <= 0)
        throw Error(ErrorCode::InvalidArgument, "cut_into_tiles: the frame is " + std::to_string(frame_width) + "x" +
                                                    std::to_string(frame_height) + ", not a positive size");
    if (tile.width <= 0 || tile.height <= 0)
        throw Error(ErrorCode::InvalidArgument, "cut_into_tiles: the tile size is " + std::to_string(tile.width) +
                                                    "x" + std::to_string(tile.height) + ", not a positive size");
    std::vector<PixelRect> tiles;
    // 64-bit steps: x + tile.width must not overflow for a huge tile.
    for (std::int64_t y = 0; y < frame_height; y += tile.height)
        for (std::int64_t x = 0; x < frame_width; x += tile.width)
            tiles.push_back({static_cast<int>(x), static_cast<int>(y),
                             static_cast<int>(std::min<std::int64_t>(tile.width, frame_width - x)),
                             static_cast<int>(std::min<std::int64_t>(tile.height, frame_height - y))});
    return tiles;
}

std::vector<DeviceShare> render_tiles(
    std::span<const CommittedScene> scenes, const RenderOptions& frame,
    const std::function<std::optional<PixelRect>()>& next_tile,
    const std::function<void(std::size_t, const PixelRect&, RenderResult&&)>& tile_done,
    const TileProgress& tile_progress) {
    if (scenes.empty()) throw Error(ErrorCode::InvalidArgument, "render_tiles: no committed scene to render with");
    if (!next_tile || !tile_done) throw Error(ErrorCode::InvalidArgument, "render_tiles: next_tile and tile_done are required");

    // One mutex serialises every callback and guards the stop flag and the
    // first exception.
    std::mutex mutex;
    bool stop = false;
    std::exception_ptr first_error;
    std::vector<DeviceShare> shares(scenes.size());
    for (std::size_t i = 0; i < scenes.size(); ++i) shares[i].device_name = describe_device(scenes[i].device());

    const auto fail = [&](std::exception_ptr e) {  // with the mutex held
        if (!first_error) first_error = std::move(e);
        stop = true;
    };

    const auto device_loop = [&](std::size_t device) {
        DeviceShare& share = shares[device];
        RenderOptions options = frame;
        options.region.reset();
        bool named = false;
        for (;;) {
            std::optional<PixelRect> tile;
            {
                std::lock_guard lock(mutex);
                if (stop) return;
                try {
                    tile = next_tile();
                } catch (...) {
                    return fail(std::current_exception());
                }
            }
            if (!tile) return;
            options.region = *tile;
            // A tile's render polls this: it stops early once another device
            // failed, and reports to tile_progress.
            options.progress = [&, device, t = *tile](double fraction) {
                std::lock_guard lock(mutex);
                if (stop) return false;
                if (!tile_progress) return true;
                return tile_progress(device, t, fraction);  // an exception fails the tile's render
            };
            const auto start = std::chrono::steady_clock::now();
            RenderResult result;
            try {
                result = scenes[device].render(options);
            } catch (...) {
                std::lock_guard lock(mutex);
                return fail(std::current_exception());  // after a stop: a Cancelled that is not the first error
            }
            share.busy_ms += ms_since(start);
            ++share.tiles;
            share.pixels += static_cast<std::uint64_t>(tile->width) * static_cast<std::uint64_t>(tile->height);
            share.rays += result.rays;
            if (!named) {
                share.device_name = result.device_name;
                named = true;
            }
            std::lock_guard lock(mutex);
            if (stop) return;
            try {
                tile_done(device, *tile, std::move(result));
            } catch (...) {
                return fail(std::current_exception());
            }
        }
    };

    std::vector<std::thread> threads;
    threads.reserve(scenes.size());
    try {
        for (std::size_t i = 0; i < scenes.size(); ++i)
            threads.emplace_back([&, i] {
                try {
                    device_loop(i);
                } catch (...) {  // outside the render and the callbacks (bad_alloc): never terminate
                    std::lock_guard lock(mutex);
                    fail(std::current_exception());
                }
            });
    } catch (...) {  // a thread that could not start: stop the others
        std::lock_guard lock(mutex);
        fail(std::current_exception());
    }
    for (std::thread& t : threads) t.join();
    if (first_error) std::rethrow_exception(first_error);
    return shares;
}

std::vector<Device> open_devices(const std::string& list) {
    std::vector<std::string> names;
    std::stringstream in(list);
    for (std::string item; std::getline(in, item, ',');) names.push_back(trimmed(item));
    if (!list.empty() && list.back() == ',') names.push_back({});
    if (names.empty() || (names.size() == 1 && names[0].empty()))
        throw Error(ErrorCode::Device, "device list '" + list + "' names no device");

    std::vector<Device> devices;
    std::set<std::string> ids;
    const auto add = [&](Device d, const std::string& named_as) {
        if (!ids.insert(d.info().id).second)
            throw Error(ErrorCode::Device, "device list '" + list + "' names device " + d.info().id + " twice (" +
                                               named_as + " is one already opened); name each device once");
        devices.push_back(std::move(d));
    };
    const auto open = [&](const std::string& name) {
        try {
            return Device::open(name);
        } catch (const Error& e) {
            throw Error(e.code(), "device list '" + list + "': " + e.what());
        }
    };
    for (const std::string& name : names) {
        if (name.empty()) throw Error(ErrorCode::Device, "device list '" + list + "' has an empty name");
        if (name == "all") {
            for (const DeviceInfo& info : list_devices()) add(open(info.id), "'all' includes " + info.id + ", which");
        } else {
            add(open(name), "'" + name + "'");
        }
    }
    return devices;
}

MultiDeviceScene MultiDeviceScene::commit(std::span<const Device> devices, const Scene& scene,
                                          const RenderOptions& options) {
    if (devices.empty()) throw Error(ErrorCode::InvalidArgument, "MultiDeviceScene: no device to commit on");
    std::vector<CommittedScene> scenes;
    scenes.reserve(devices.size());
    // The first device builds or loads the tree (and saves it); the others take it in memory.
    scenes.push_back(CommittedScene::commit(devices[0], scene, options));
    RenderOptions others = options;
    if (const std::shared_ptr<const KdTree>& tree = scenes[0].state()->tree) {
        others.tree_in_memory = tree;
        others.load_tree.reset();
        others.save_tree.reset();
        others.tree_cache_dir.reset();
    }
    for (std::size_t i = 1; i < devices.size(); ++i) scenes.push_back(CommittedScene::commit(devices[i], scene, others));
    return MultiDeviceScene(std::move(scenes));
}

void MultiDeviceScene::update(const Scene& scene) {
    const std::shared_ptr<const KdTree> before = scenes_[0].state()->tree;
    scenes_[0].update(scene);
    const std::shared_ptr<const KdTree>& after = scenes_[0].state()->tree;
    for (std::size_t i = 1; i < scenes_.size(); ++i) {
        if (after && after != before) {
            // New geometry, built once: the others commit it with that tree.
            RenderOptions o = scenes_[i].state()->options;
            o.tree_in_memory = after;
            o.load_tree.reset();
            o.save_tree.reset();
            o.tree_cache_dir.reset();
            scenes_[i] = CommittedScene::commit(scenes_[i].device(), scene, o);
        } else {
            scenes_[i].update(scene);  // shading only, or no tree at all
        }
    }
}

RenderResult MultiDeviceScene::render(const RenderOptions& frame, TileSize tile) const {
    const detail::CommittedSceneState& first = *scenes_[0].state();
    const RenderSettings settings = detail::frame_settings(first.scene_settings, frame, first.scene_name);
    detail::check_region(frame.region, settings.width, settings.height);
    const PixelRect area = frame.region.value_or(PixelRect{0, 0, settings.width, settings.height});
    std::vector<PixelRect> tiles = cut_into_tiles(area.width, area.height, tile);
    for (PixelRect& t : tiles) {
        t.x += area.x;
        t.y += area.y;
    }

    const auto start = std::chrono::steady_clock::now();
    RenderResult out;
    out.image = Image(area.width, area.height);
    const std::size_t pixels = static_cast<std::size_t>(area.width) * static_cast<std::size_t>(area.height);
    if (frame.want_ids) {
        out.ids.assign(pixels, -1);
        out.hit_t.assign(pixels, 0.0f);
    }

    // Progress: pixels of finished tiles plus the tiles in flight's share.
    std::vector<double> in_flight(scenes_.size(), 0.0);
    std::uint64_t pixels_done = 0;
    const auto report = [&] {
        double done = static_cast<double>(pixels_done);
        for (double p : in_flight) done += p;
        return frame.progress(std::min(1.0, done / static_cast<double>(pixels)));
    };
    TileProgress tile_progress;
    if (frame.progress)
        tile_progress = [&](std::size_t device, const PixelRect& t, double fraction) {
            in_flight[device] = fraction * t.width * t.height;
            return report();
        };

    // The work of commit() or update() each device reports with its first
    // tile (after the frame, for a device that got none), and the device work
    // of its tiles.
    const auto add_device_work = [&](std::size_t device, RenderResult& r) {
        out.builds += r.builds;
        out.build_ms += r.build_ms;
        // The others take the first device's tree in memory: only its own says whether it came from a file.
        if (device == 0) out.tree_loaded = out.tree_loaded || r.tree_loaded;
        out.compiles += r.compiles;
        out.compile_ms += r.compile_ms;
        out.upload_ms += r.upload_ms;
        out.geometry_upload_bytes += r.geometry_upload_bytes;
        for (std::string& w : r.warnings)
            if (std::find(out.warnings.begin(), out.warnings.end(), w) == out.warnings.end())
                out.warnings.push_back(std::move(w));
    };

    std::size_t next = 0;
    bool first_tile = true;
    const auto tile_done = [&](std::size_t device, const PixelRect& t, RenderResult&& r) {
        // Rows of the tile into the frame (or region) at its place.
        for (int row = 0; row < t.height; ++row) {
            const std::size_t src = static_cast<std::size_t>(row) * t.width;
            const std::size_t dst = static_cast<std::size_t>(t.y - area.y + row) * area.width + (t.x - area.x);
            std::copy_n(r.image.rgb.begin() + static_cast<std::ptrdiff_t>(3 * src), 3 * t.width,
                        out.image.rgb.begin() + static_cast<std::ptrdiff_t>(3 * dst));
            if (frame.want_ids) {
                std::copy_n(r.ids.begin() + static_cast<std::ptrdiff_t>(src), t.width,
                            out.ids.begin() + static_cast<std::ptrdiff_t>(dst));
                std::copy_n(r.hit_t.begin() + static_cast<std::ptrdiff_t>(src), t.width,
                            out.hit_t.begin() + static_cast<std::ptrdiff_t>(dst));
            }
        }
        out.rays += r.rays;
        out.launches += r.launches;
        add_device_work(device, r);
        if (first_tile) {
            out.features = r.features;
            out.tree_stats = r.tree_stats;
            first_tile = false;
        }
        if (out.kernel_options.empty() && !r.kernel_options.empty()) {
            out.kernel_options = r.kernel_options;
            out.kernel_cache_hit = r.kernel_cache_hit;
            out.kernel_resources = std::move(r.kernel_resources);
            out.traversal_stack_bytes = r.traversal_stack_bytes;
        }
        pixels_done += static_cast<std::uint64_t>(t.width) * static_cast<std::uint64_t>(t.height);
        in_flight[device] = 0.0;
        if (frame.progress && !report()) throw Error(ErrorCode::Cancelled, "render cancelled");
    };

    RenderOptions per_tile = frame;
    per_tile.progress = nullptr;
    out.device_shares = render_tiles(
        scenes_, per_tile,
        [&]() -> std::optional<PixelRect> {
            if (next == tiles.size()) return std::nullopt;
            return tiles[next++];
        },
        tile_done, tile_progress);
    // A device that got no tile (another took them all) reports its work
    // with this frame, not with the next one it takes part in.
    for (std::size_t i = 0; i < scenes_.size(); ++i) {
        if (out.device_shares[i].tiles != 0) continue;
        RenderResult pending;
        detail::report_pending_work(*scenes_[i].state(), pending);
        add_device_work(i, pending);
    }

    out.render_ms = ms_since(start);
    for (const DeviceShare& s : out.device_shares) {
        if (!out.device_name.empty()) out.device_name += " + ";
        out.device_name += s.device_name;
    }
    return out;
}

}  // namespace kdrt
