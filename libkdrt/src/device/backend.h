// The interface between the dispatch layer (src/render: Device,
// CommittedScene, render()) and a device: the C++ reference (src/cpu) and
// OpenCL (src/opencl) each implement it. Kept here, outside src/render, so the
// devices can include it without including the dispatch layer.
//
// Division of work. The dispatch layer prepares the scene (PreparedScene),
// provides the kd-tree (build, file, cache or in memory), keeps both alive
// for as long as the SceneBackend made from them, counts the work in
// CommitStats, and maps object ids to the public ones (PreparedScene::
// public_ids) when they leave the library. A backend sees internal ids only
// (positions in SceneGeometry: spheres, then triangles) and reports them
// as such, in RenderResult::ids and in QueryHit::object.
#pragma once

#include "device/accel.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/device.h>
#include <kdrt/frame_options.h>
#include <kdrt/kd_tree.h>
#include <kdrt/layout.h>
#include <kdrt/render_result.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace kdrt::detail {

// Device work done by a commit or an update, added to CommitStats and
// reported by the next frame's RenderResult.
struct BackendWork {
    std::uint64_t compiles = 0;           // programs built or loaded from the kernel cache
    std::uint64_t geometry_uploads = 0;   // geometry and tree copied to the device
    std::uint64_t geometry_upload_bytes = 0;
    std::uint64_t shading_uploads = 0;    // camera, lights, materials only
    double compile_ms = 0.0, upload_ms = 0.0;
    std::vector<std::string> warnings;    // of a commit (an unusable kernel cache): the next frame reports them
};

// A scene made ready on a device. `scene` and the structures given to commit(), and
// the DeviceBackend, stay alive and at the same address until the
// SceneBackend is destroyed; between
// calls the dispatch layer may change the scene's shading fields (camera,
// settings, materials, lights, features), never its geometry.
class SceneBackend {
public:
    virtual ~SceneBackend() = default;

    // One frame of the committed scene with the commit's options and
    // `frame` (its settings and features already in the PreparedScene). The
    // result's stats.compile_ms, upload_ms, compiles and
    // geometry_upload_bytes are this call's own work (0 when it reused what
    // commit or update made). frame.progress may cancel (kdrt::Error(Cancelled)).
    virtual RenderResult render(const FrameOptions& frame) = 0;

    // The scene's shading fields changed (features included); the geometry
    // did not. Upload what the device keeps of them; add the work to `work`.
    virtual void update_shading(BackendWork& work) = 0;

    // The scene's objects moved and the BVH given to commit() was refit to
    // them in place (the same objects, the same nodes and leaves, new boxes
    // and positions). Bring what the device keeps up to date and return
    // true, or return false when it cannot: the caller then commits anew.
    virtual bool refit(BackendWork&) { return false; }

    // The memory this backend keeps of the scene (CommitStats::device_bytes).
    virtual std::uint64_t device_bytes() const = 0;

    // Ray queries on host spans, world space (see kdrt/ray_query.h); hit
    // ids are internal. The sizes are checked by the caller. Safe to call
    // from several threads at once. A backend without them throws
    // kdrt::Error(Unsupported).
    virtual void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const = 0;
    virtual void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const = 0;

    // Hits per ray, every hit (ray_splits, hits nearest first per ray) and
    // closest points (kdrt/ray_query.h), ids internal, sizes checked by the
    // caller. A backend without them throws kdrt::Error(Unsupported) naming
    // the query and the device.
    virtual void count_hits(std::span<const QueryRay> rays, std::span<std::uint32_t> counts) const = 0;
    // count_hits with a geometry's hits at one t counted once (geometry_of:
    // each internal id's geometry). False where the backend has no such pass:
    // the caller then counts the merged hit lists.
    virtual bool count_hits_once_per_geometry(std::span<const QueryRay>, std::span<std::uint32_t>,
                                              std::span<const std::uint32_t>) const {
        return false;
    }
    virtual void all_hits(std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                          std::vector<QueryHit>& hits) const = 0;
    virtual void closest_points(std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) const = 0;
};

// A device opened once (kdrt::Device), shared by the scenes committed on it.
// Thread-safe: commit() may be called from several threads at once.
class DeviceBackend {
public:
    virtual ~DeviceBackend() = default;

    virtual const DeviceInfo& info() const = 0;
    virtual bool is_opencl() const = 0;
    // The SAH cost of a triangle test in this device's leaves, for trees built
    // for it (KdBuildConfig::intersection_cost 0).
    virtual double triangle_cost() const = 0;

    // Makes `scene` ready for frames and queries through `accel` (its kd-tree
    // or its BVH as options.accel says; neither for Traversal::None) with
    // `options` (traversal, accuracy, kernel cache, query launches; the
    // structures are the caller's); adds the work done to `work`.
    virtual std::unique_ptr<SceneBackend> commit(const PreparedScene& scene, AccelRef accel,
                                                 const CommitOptions& options, BackendWork& work) = 0;
};

}  // namespace kdrt::detail
