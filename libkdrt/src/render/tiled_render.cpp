// kdrt/tiled_render.h: a frame cut into tiles that several devices pull from
// one counter, each tile rendered with FrameOptions::region (bit for bit the
// device's whole-frame pixels), and the scene committed once per device with
// one shared kd-tree or BVH.
#include "common/ms_since.h"
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

using detail::CommittedSceneAccess;
using detail::ms_since;

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
    std::span<const CommittedScene> scenes, const FrameOptions& frame,
    const std::function<std::optional<PixelRect>()>& next_tile,
    const std::function<void(std::size_t, const PixelRect&, RenderResult&&)>& tile_done,
    const TileProgress& tile_progress) {
    if (scenes.empty()) throw Error(ErrorCode::InvalidArgument, "render_tiles: no committed scene to render with");
    if (!next_tile || !tile_done) throw Error(ErrorCode::InvalidArgument, "render_tiles: next_tile and tile_done are required");
    for (const CommittedScene& scene : scenes) CommittedSceneAccess::state(scene, "render_tiles");  // none moved from

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
        FrameOptions options = frame;
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
            share.rays += result.stats.rays;
            if (!named) {
                share.device_name = result.stats.device_name;
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

namespace {

// The options a device other than the first commits with: the first one's
// tree in memory instead of any file, cache or build.
CommitOptions with_shared_tree(CommitOptions options, const std::shared_ptr<const KdTree>& tree,
                               const std::shared_ptr<WideBvh>& bvh) {
    if (tree || bvh) options.tree_files = {};
    if (tree) options.tree_files.in_memory = tree;
    return options;
}

// The tiles of `area` (a frame, or a region of it) in frame coordinates.
std::vector<PixelRect> tiles_of(const PixelRect& area, TileSize tile) {
    std::vector<PixelRect> tiles = cut_into_tiles(area.width, area.height, tile);
    for (PixelRect& t : tiles) {
        t.x += area.x;
        t.y += area.y;
    }
    return tiles;
}

// A frame (or region) assembled from its tiles' results, with their
// statistics summed.
class TiledFrame {
public:
    TiledFrame(const PixelRect& area, bool want_ids) : area_(area), want_ids_(want_ids) {
        result_.image = Image(area.width, area.height);
        const std::size_t pixels = static_cast<std::size_t>(area.width) * static_cast<std::size_t>(area.height);
        if (want_ids) {
            result_.ids.assign(pixels, -1);
            result_.hit_t.assign(pixels, 0.0f);
        }
    }

    // A tile's pixels at their place, and what its render did.
    void add_tile(std::size_t device, const PixelRect& t, RenderResult&& r) {
        copy_pixels(t, r);
        RenderStats& out = result_.stats;
        out.rays += r.stats.rays;
        out.opencl.launches += r.stats.opencl.launches;
        add_device_work(device, r);
        if (first_tile_) {
            out.features = r.stats.features;
            out.tree_stats = r.stats.tree_stats;
            out.bvh_stats = r.stats.bvh_stats;
            first_tile_ = false;
        }
        OpenClStats& cl = r.stats.opencl;
        if (out.opencl.kernel_options.empty() && !cl.kernel_options.empty()) {
            out.opencl.kernel_options = cl.kernel_options;
            out.opencl.kernel_cache_hit = cl.kernel_cache_hit;
            out.opencl.kernel_resources = std::move(cl.kernel_resources);
            out.opencl.traversal_stack_bytes = cl.traversal_stack_bytes;
        }
    }

    // The work of commit() or update() a device reports with its first tile
    // (after the frame, for a device that got none), and the device work of
    // its tiles.
    void add_device_work(std::size_t device, RenderResult& r) {
        RenderStats& out = result_.stats;
        out.builds += r.stats.builds;
        out.build_ms += r.stats.build_ms;
        // The others take the first device's tree in memory: only its own says whether it came from a file.
        if (device == 0) out.tree_loaded = out.tree_loaded || r.stats.tree_loaded;
        out.compiles += r.stats.compiles;
        out.compile_ms += r.stats.compile_ms;
        out.upload_ms += r.stats.upload_ms;
        out.geometry_upload_bytes += r.stats.geometry_upload_bytes;
        for (std::string& w : r.warnings)
            if (std::find(result_.warnings.begin(), result_.warnings.end(), w) == result_.warnings.end())
                result_.warnings.push_back(std::move(w));
    }

    RenderResult& result() { return result_; }

private:
    // Rows of the tile into the frame (or region) at its place.
    void copy_pixels(const PixelRect& t, const RenderResult& r) {
        for (int row = 0; row < t.height; ++row) {
            const std::size_t src = static_cast<std::size_t>(row) * t.width;
            const std::size_t dst = static_cast<std::size_t>(t.y - area_.y + row) * area_.width + (t.x - area_.x);
            std::copy_n(r.image.rgb.begin() + static_cast<std::ptrdiff_t>(3 * src), 3 * t.width,
                        result_.image.rgb.begin() + static_cast<std::ptrdiff_t>(3 * dst));
            if (want_ids_) {
                std::copy_n(r.ids.begin() + static_cast<std::ptrdiff_t>(src), t.width,
                            result_.ids.begin() + static_cast<std::ptrdiff_t>(dst));
                std::copy_n(r.hit_t.begin() + static_cast<std::ptrdiff_t>(src), t.width,
                            result_.hit_t.begin() + static_cast<std::ptrdiff_t>(dst));
            }
        }
    }

    PixelRect area_;
    bool want_ids_;
    bool first_tile_ = true;
    RenderResult result_;
};

// A frame's progress over its tiles: the pixels of finished tiles plus the
// tiles in flight's share, reported to the frame's callback.
class TiledProgress {
public:
    TiledProgress(std::size_t devices, std::size_t pixels, const std::function<bool(double)>& report)
        : in_flight_(devices, 0.0), pixels_(static_cast<double>(pixels)), report_(report) {}

    // What render_tiles calls while a tile renders (none without a callback).
    TileProgress tile_progress() {
        if (!report_) return {};
        return [this](std::size_t device, const PixelRect& t, double fraction) {
            in_flight_[device] = fraction * t.width * t.height;
            return report();
        };
    }

    // A tile done; Error(Cancelled) when the callback says stop.
    void tile_done(std::size_t device, const PixelRect& t) {
        pixels_done_ += static_cast<std::uint64_t>(t.width) * static_cast<std::uint64_t>(t.height);
        in_flight_[device] = 0.0;
        if (report_ && !report()) throw Error(ErrorCode::Cancelled, "render cancelled");
    }

private:
    bool report() {
        double done = static_cast<double>(pixels_done_);
        for (double p : in_flight_) done += p;
        return report_(std::min(1.0, done / pixels_));
    }

    std::vector<double> in_flight_;  // by device
    std::uint64_t pixels_done_ = 0;
    double pixels_;
    const std::function<bool(double)>& report_;
};

// Every scene of a MultiDeviceScene, none moved from, named in errors as `call`.
void check_scenes(std::span<const CommittedScene> scenes, const char* call) {
    if (scenes.empty())
        throw Error(ErrorCode::InvalidArgument,
                    std::string(call) + ": the kdrt::MultiDeviceScene was moved from and holds no scene");
    for (const CommittedScene& scene : scenes) CommittedSceneAccess::state(scene, call);
}

}  // namespace

MultiDeviceScene MultiDeviceScene::commit(std::span<const Device> devices, const Scene& scene,
                                          const CommitOptions& options) {
    if (devices.empty()) throw Error(ErrorCode::InvalidArgument, "MultiDeviceScene: no device to commit on");
    std::vector<CommittedScene> scenes;
    scenes.reserve(devices.size());
    // The first device builds or loads the tree or BVH (and saves it); the others take it in memory.
    scenes.push_back(CommittedScene::commit(devices[0], scene, options));
    const detail::CommittedSceneState& first = CommittedSceneAccess::state(scenes[0], "MultiDeviceScene::commit");
    const CommitOptions others = with_shared_tree(options, first.tree, first.bvh);
    for (std::size_t i = 1; i < devices.size(); ++i)
        scenes.push_back(CommittedSceneAccess::commit(devices[i], scene, others, FrameOptions{}, first.bvh));
    return MultiDeviceScene(std::move(scenes));
}

void MultiDeviceScene::update(const Scene& scene) {
    check_scenes(scenes_, "MultiDeviceScene::update");
    const detail::CommittedSceneState& first = CommittedSceneAccess::state(scenes_[0], "update");
    const std::shared_ptr<const KdTree> tree_before = first.tree;
    const std::shared_ptr<WideBvh> bvh_before = first.bvh;
    scenes_[0].update(scene);
    for (std::size_t i = 1; i < scenes_.size(); ++i) {
        if ((first.tree && first.tree != tree_before) || (first.bvh && first.bvh != bvh_before)) {
            // New geometry, built once: the others commit it with that structure.
            const detail::CommittedSceneState& s = CommittedSceneAccess::state(scenes_[i], "update");
            scenes_[i] = CommittedSceneAccess::commit(s.device, scene, with_shared_tree(s.options, first.tree, first.bvh),
                                                      s.frame_size, first.bvh);
        } else {
            scenes_[i].update(scene);  // shading only, a refit of the shared BVH (the same boxes again), or no structure
        }
    }
}

RenderResult MultiDeviceScene::render(const FrameOptions& frame, TileSize tile) const {
    check_scenes(scenes_, "MultiDeviceScene::render");
    const detail::CommittedSceneState& first = CommittedSceneAccess::state(scenes_[0], "MultiDeviceScene::render");
    const RenderSettings settings = detail::frame_settings(first.scene_settings, frame, first.scene_name);
    detail::check_region(frame.region, settings.width, settings.height);
    const PixelRect area = frame.region.value_or(PixelRect{0, 0, settings.width, settings.height});
    const std::vector<PixelRect> tiles = tiles_of(area, tile);

    const auto start = std::chrono::steady_clock::now();
    TiledFrame out(area, frame.want_ids);
    TiledProgress progress(scenes_.size(), static_cast<std::size_t>(area.width) * static_cast<std::size_t>(area.height),
                           frame.progress);
    std::size_t next = 0;
    FrameOptions per_tile = frame;
    per_tile.progress = nullptr;
    RenderStats& stats = out.result().stats;
    stats.device_shares = render_tiles(
        scenes_, per_tile,
        [&]() -> std::optional<PixelRect> {
            if (next == tiles.size()) return std::nullopt;
            return tiles[next++];
        },
        [&](std::size_t device, const PixelRect& t, RenderResult&& r) {
            out.add_tile(device, t, std::move(r));
            progress.tile_done(device, t);
        },
        progress.tile_progress());
    // A device that got no tile (another took them all) reports its work
    // with this frame, not with the next one it takes part in.
    for (std::size_t i = 0; i < scenes_.size(); ++i) {
        if (stats.device_shares[i].tiles != 0) continue;
        RenderResult pending;
        detail::report_pending_work(CommittedSceneAccess::state(scenes_[i], "MultiDeviceScene::render"), pending);
        out.add_device_work(i, pending);
    }

    stats.render_ms = ms_since(start);
    for (const DeviceShare& s : stats.device_shares) {
        if (!stats.device_name.empty()) stats.device_name += " + ";
        stats.device_name += s.device_name;
    }
    return std::move(out.result());
}

}  // namespace kdrt
