// What a kdrt::CommittedScene holds: the prepared scene, its tree and the
// device's SceneBackend made from them, the counts of the work done, and the
// work done since the last frame (reported by the next frame's RenderResult);
// and the library's way in to it (kdrt/committed_scene.h declares
// CommittedSceneAccess its friend).
#pragma once

#include "device/backend.h"
#include "scene/geometry_digest.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/frame_options.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace kdrt::detail {

// Work of commit() or update() not yet reported by a frame (what a
// RenderResult reports of it): the tree's, the device's, and the warnings of both.
struct PendingWork {
    std::uint64_t builds = 0, refits = 0;
    double build_ms = 0.0;
    bool tree_loaded = false;
    std::uint64_t compiles = 0, geometry_upload_bytes = 0;
    double compile_ms = 0.0, upload_ms = 0.0;
    std::vector<std::string> warnings;
};

struct CommittedSceneState {
    explicit CommittedSceneState(Device d) : device(std::move(d)) {}

    Device device;             // keeps the DeviceBackend alive for `backend`
    CommitOptions options;     // the commit's (progress dropped)
    // The frame size, depth and samples the scene is prepared with (the
    // kernels are specialised for the depth): the last frame's; at commit the
    // first frame's where it is known (render()), else the scene's own.
    FrameOptions frame_size;
    std::string scene_name;    // for the frame settings' error messages
    RenderSettings scene_settings;  // the scene's own, before any frame's overrides
    PreparedScene prepared;    // at a fixed address: the backend refers to it
    GeometryDigest digest;     // of the objects `prepared` was made from, as given
    std::shared_ptr<const KdTree> tree;  // Accel::KdTree; null for Traversal::None without build_tree
    std::optional<KdTreeStats> tree_stats;
    std::shared_ptr<WideBvh> bvh;        // Accel::Bvh; null for Traversal::None without build_tree
    std::optional<BvhStats> bvh_stats;
    CommitStats stats;
    PendingWork pending;
    std::unique_ptr<SceneBackend> backend;  // last: destroyed before the scene and tree it refers to;
                                            // null after an update() that failed

private:
    mutable std::mutex geometry_of_mutex_;
    mutable std::optional<std::vector<std::uint32_t>> geometry_of_;
public:

    AccelRef accel() const { return {tree.get(), bvh.get()}; }

    // Each internal object's geometry (count_hits with OncePerGeometry),
    // made from `prepared` on first use and kept; update() drops it.
    const std::vector<std::uint32_t>& geometry_of() const;
    void forget_geometry_of() {
        const std::lock_guard lock(geometry_of_mutex_);
        geometry_of_.reset();
    }

    SceneBackend& ready_backend() const {
        if (!backend)
            throw Error(ErrorCode::InvalidArgument,
                        "scene '" + scene_name + "': its last update() failed; update() it again before using it");
        return *backend;
    }
};

struct CommittedSceneAccess {
    static CommittedScene make(std::shared_ptr<CommittedSceneState> state) { return CommittedScene(std::move(state)); }

    // The scene's state; kdrt::Error(InvalidArgument) naming `call` for a
    // moved-from CommittedScene, which holds none.
    static CommittedSceneState& state(const CommittedScene& scene, const char* call) {
        if (!scene.state_)
            throw Error(ErrorCode::InvalidArgument,
                        std::string(call) + ": the kdrt::CommittedScene was moved from and holds no scene");
        return *scene.state_;
    }

    // CommittedScene::commit, with the kernels specialised for `first_frame`'s
    // depth (render(): the frame that follows compiles nothing more). With
    // Accel::Bvh, `shared_bvh` (another device's, for the same geometry) is
    // used instead of any file, cache or build.
    static CommittedScene commit(const Device& device, const Scene& scene, const CommitOptions& options,
                                 const FrameOptions& first_frame, std::shared_ptr<WideBvh> shared_bvh = nullptr);
};

// Adds what commit() or update() left to report (builds, tree loads, device
// work, warnings) to a frame's result, once: the pending work is cleared.
void report_pending_work(CommittedSceneState& s, RenderResult& result);

// Throws Error(InvalidArgument) naming the region unless it is unset or a
// non-empty rectangle inside the width x height frame.
void check_region(const std::optional<PixelRect>& region, int width, int height);

}  // namespace kdrt::detail
