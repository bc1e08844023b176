// kdrt::CommittedScene: a Scene made ready on a Device once (kd-tree or BVH
// built or loaded, kernels compiled, geometry uploaded), then traced and
// rendered many times. Cameras, lights, materials and render settings change
// between frames without a rebuild; a geometry change rebuilds the structure
// (or refits the BVH) and uploads again.
#pragma once

#include <kdrt/commit_options.h>
#include <kdrt/device.h>
#include <kdrt/export.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>
#include <kdrt/scene.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

namespace kdrt {

namespace detail {
struct CommittedSceneState;
struct CommittedSceneAccess;
}  // namespace detail

// What has been done for a committed scene so far (counts since commit()).
struct CommitStats {
    std::uint64_t geometry_passes = 0;  // preparations of the geometry: commit(), and update() when it changed
    std::uint64_t builds = 0;           // kd-tree or BVH builds
    std::uint64_t refits = 0;           // BVH refits by update() (moved objects, same topology)
    std::uint64_t tree_loads = 0;       // trees loaded from a file or the cache, or given in memory
    std::uint64_t compiles = 0;         // OpenCL programs built or loaded from the kernel cache
    std::uint64_t geometry_uploads = 0; // uploads of geometry and tree to the device
    std::uint64_t geometry_upload_bytes = 0;
    std::uint64_t shading_uploads = 0;  // uploads of camera, lights, materials only
    double build_ms = 0.0, compile_ms = 0.0, upload_ms = 0.0;  // totals
    // Not a count: the memory the device keeps of the scene as of the last
    // commit() or update(), beside the prepared geometry and the structure
    // (tree() or bvh_stats()): on the cpu device its packed leaf blocks and a
    // BVH's copy of the nodes that refer to them, in host memory; on OpenCL
    // the scene's buffers on the device. 0 after a failed update().
    std::uint64_t device_bytes = 0;
};

// A handle: copies share the committed scene. A moved-from CommittedScene
// throws kdrt::Error(InvalidArgument) from every call, and so do
// intersect(), occluded() and render_tiles() given one.
class KDRT_API CommittedScene {
public:
    // Prepares `scene` on `device` with `options`: the tree is built, loaded
    // (options.tree_files) or taken in memory, the kernels are compiled for
    // the scene's own settings (a frame that asks for another depth compiles
    // its own variant on OpenCL), the geometry is uploaded. options.progress
    // reports build and upload; returning false cancels with
    // kdrt::Error(Cancelled). Throws kdrt::Error on bad input.
    static CommittedScene commit(const Device& device, const Scene& scene, const CommitOptions& options = {});

    // Takes the scene's camera, lights, materials and settings. Whether the
    // objects changed is learnt from a 128-bit digest of them as given
    // (spheres, triangles, meshes with their positions, normals and
    // materials, Scene::added), one pass at memory speed (some 2-3 ms for 1M
    // triangles); unchanged, nothing of the geometry is touched again
    // (stats().geometry_passes stays). Changed, the scene is prepared again;
    // then the tree is rebuilt and everything uploaded when the geometry's
    // fingerprint, working frame or object ids changed (a tree given by file
    // or in memory for the old geometry is not used again), or only the
    // geometry uploaded again with the same tree when just the triangles'
    // materials or normals did. A material change that switches an effect on
    // (glass in a scene without it) compiles another kernel variant on OpenCL.
    // With Accel::Bvh, objects that only moved (the same objects with the same
    // ids, vertices elsewhere) refit the BVH in place instead of rebuilding it
    // (stats().refits), unless the refit hierarchy's SAH cost has grown
    // threefold, when it is rebuilt. `progress` hears the fraction done of a
    // rebuild and the upload; returning false cancels with
    // kdrt::Error(Cancelled), as a failed update: the scene must then be
    // updated again before it is used.
    void update(const Scene& scene, const std::function<bool(double)>& progress = {});

    // One frame with the commit's options and these. The result's
    // stats.build_ms/compile_ms/upload_ms and builds/compiles/
    // geometry_upload_bytes are this frame's share (0 when nothing was
    // redone): its own work plus that of the commit() or update() before it,
    // which the next frame reports. On OpenCL devices the scene keeps its
    // frame buffers (image, id map, ray queues, the largest asked for so far)
    // for the next frame, until it is destroyed.
    RenderResult render(const FrameOptions& frame = {}) const;

    const CommitStats& stats() const;
    const KdTree* tree() const;               // null for Accel::Bvh, and for Traversal::None without build_tree
    std::optional<BvhStats> bvh_stats() const;  // Accel::Bvh: the hierarchy's statistics; else empty
    std::uint64_t geometry_fingerprint() const;  // the one tree files are tied to
    const Device& device() const;

private:
    friend struct detail::CommittedSceneAccess;
    explicit CommittedScene(std::shared_ptr<detail::CommittedSceneState> state) : state_(std::move(state)) {}
    std::shared_ptr<detail::CommittedSceneState> state_;
};

// The fingerprint of a scene's geometry that tree files carry (XXH3-64 of its
// float geometry in the working frame); equal for scenes with equal geometry.
KDRT_API std::uint64_t geometry_fingerprint(const Scene& scene);

// Builds the kd-tree a commit of `scene` with `options` and Accel::KdTree
// would build (no ropes unless options.traversal is Ropes), without
// committing; options.accel is not read. options.progress
// reports the build unless options.tree.progress is set.
KDRT_API KdTree build_scene_tree(const Scene& scene, const CommitOptions& options = {});

}  // namespace kdrt
