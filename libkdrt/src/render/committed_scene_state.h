// What a kdrt::CommittedScene holds: the prepared scene, its tree and the
// device's SceneBackend made from them, the counts of the work done, and the
// work done since the last frame (reported by the next frame's RenderResult).
#pragma once

#include "device/backend.h"
#include "scene/geometry_digest.h"
#include "scene/prepared_scene.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device_handle.h>
#include <kdrt/error.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace kdrt::detail {

// Work of commit() or update() not yet reported by a frame (what a
// RenderResult reports of it): the tree's, the device's, and the warnings of both.
struct PendingWork {
    std::uint64_t builds = 0;
    double build_ms = 0.0;
    bool tree_loaded = false;
    std::uint64_t compiles = 0, geometry_upload_bytes = 0;
    double compile_ms = 0.0, upload_ms = 0.0;
    std::vector<std::string> warnings;
};

struct CommittedSceneState {
    explicit CommittedSceneState(Device d) : device(std::move(d)) {}

    Device device;             // keeps the DeviceBackend alive for `backend`
    RenderOptions options;     // the commit's scene-level fields (progress dropped)
    std::string scene_name;    // for the frame settings' error messages
    RenderSettings scene_settings;  // the scene's own, before any frame's overrides
    PreparedScene prepared;    // at a fixed address: the backend refers to it
    GeometryDigest digest;     // of the objects `prepared` was made from, as given
    std::shared_ptr<const KdTree> tree;  // null for Traversal::None without build_tree
    std::optional<KdTreeStats> tree_stats;
    CommitStats stats;
    PendingWork pending;
    std::unique_ptr<SceneBackend> backend;  // last: destroyed before the scene and tree it refers to;
                                            // null after an update() that failed

    SceneBackend& ready_backend() const {
        if (!backend)
            throw Error(ErrorCode::InvalidArgument,
                        "scene '" + scene_name + "': its last update() failed; update() it again before using it");
        return *backend;
    }
};

// Adds what commit() or update() left to report (builds, tree loads, device
// work, warnings) to a frame's result, once: the pending work is cleared.
void report_pending_work(CommittedSceneState& s, RenderResult& result);

// Throws Error(InvalidArgument) naming the region unless it is unset or a
// non-empty rectangle inside the width x height frame.
void check_region(const std::optional<PixelRect>& region, int width, int height);

}  // namespace kdrt::detail
