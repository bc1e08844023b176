// kdrt::CommittedScene: prepare, provide the tree and commit on the device
// once; then frames and shading updates without a rebuild.
#include "render/committed_scene_state.h"
#include "render/device_state.h"
#include "bvh/bvh_refit.h"
#include "bvh/bvh_stats.h"
#include "kdtree/tree_provider.h"
#include "scene/geometry_digest.h"
#include "scene/scene_validation.h"

#include <kdrt/commit_options.h>
#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/frame_options.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace kdrt {

namespace {

using detail::CommittedSceneAccess;
using detail::CommittedSceneState;
using detail::DeviceAccess;

// The commit's options with the builder reporting to options.progress (unless
// the builder has its own callback); the builder calls it from one builder
// thread at a time.
CommitOptions with_build_progress(const CommitOptions& options) {
    CommitOptions o = options;
    if (o.progress && !o.tree.progress) o.tree.progress = o.progress;
    if (o.progress && !o.bvh.progress) o.bvh.progress = o.progress;
    return o;
}

bool needs_tree(const CommitOptions& o) {
    // A tree given by file or in memory is always checked, even for Traversal::None.
    return o.traversal != Traversal::None || o.build_tree || o.tree_files.save || o.tree_files.load ||
           o.tree_files.in_memory;
}

// Adds a backend's work to the scene's totals.
void add(CommitStats& totals, const detail::BackendWork& w) {
    totals.compiles += w.compiles;
    totals.geometry_uploads += w.geometry_uploads;
    totals.geometry_upload_bytes += w.geometry_upload_bytes;
    totals.shading_uploads += w.shading_uploads;
    totals.compile_ms += w.compile_ms;
    totals.upload_ms += w.upload_ms;
}

// A backend's work to report with the next frame.
void add_pending(detail::PendingWork& p, const detail::BackendWork& w) {
    p.compiles += w.compiles;
    p.geometry_upload_bytes += w.geometry_upload_bytes;
    p.compile_ms += w.compile_ms;
    p.upload_ms += w.upload_ms;
    p.warnings.insert(p.warnings.end(), w.warnings.begin(), w.warnings.end());
}

// The scene made ready on the device from s.prepared and s.tree.
void commit_backend(CommittedSceneState& s, const CommitOptions& options) {
    detail::BackendWork work;
    s.backend = DeviceAccess::backend(s.device, "CommittedScene::commit").commit(s.prepared, s.accel(), options, work);
    s.stats.device_bytes = s.backend->device_bytes();
    add(s.stats, work);
    add_pending(s.pending, work);
}

// Counts a structure's build or load, and its warning.
template <class Provided>
void count_provided(CommittedSceneState& s, const Provided& provided) {
    s.pending.build_ms += provided.build_ms;
    s.stats.build_ms += provided.build_ms;
    if (provided.loaded) {
        ++s.stats.tree_loads;
        s.pending.tree_loaded = true;
    } else {
        ++s.stats.builds;
        ++s.pending.builds;
    }
    if (!provided.cache_warning.empty()) s.pending.warnings.push_back(provided.cache_warning);
}

// The structure (kd-tree or BVH) and backend for the scene in s.prepared (any
// previous backend is gone). A kd-tree is built for this device: a triangle
// cost of 0 becomes its own.
void commit_geometry(CommittedSceneState& s, const CommitOptions& given, std::shared_ptr<WideBvh> shared_bvh = nullptr) {
    CommitOptions options = given;
    options.tree = given.tree.with_triangle_cost(s.device.triangle_cost());
    s.tree.reset();
    s.tree_stats.reset();
    s.bvh.reset();
    s.bvh_stats.reset();
    if (needs_tree(options) && options.accel == Accel::Bvh) {
        detail::ProvidedBvh provided;
        if (shared_bvh) {
            provided.bvh = std::move(shared_bvh);
            provided.loaded = true;
        } else {
            provided = detail::provide_bvh(s.prepared, with_build_progress(options));
        }
        s.bvh = std::move(provided.bvh);
        s.bvh_stats = bvh_stats(*s.bvh);
        count_provided(s, provided);
    } else if (needs_tree(options)) {
        detail::ProvidedTree provided = detail::provide_tree(s.prepared, with_build_progress(options));
        s.tree = std::move(provided.tree);
        s.tree_stats = kd_tree_stats(*s.tree, options.tree);
        count_provided(s, provided);
    }
    commit_backend(s, options);
}

// The BVH refit to s.prepared's objects, which moved but are the same objects
// (same ids, same kinds). False when a rebuild is due instead: the refit's
// SAH cost has grown past kBvhRebuildSahRatio, or an object gained a box.
bool refit_geometry(CommittedSceneState& s, const CommitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    BvhRefitResult refit;
    try {
        // Each leaf's box from the moved geometry as the refit reaches it.
        const detail::PreparedScene& scene = s.prepared;
        auto leaf_box = [&scene](std::span<const std::uint32_t> ids) { return scene.objects_bound(ids); };
        refit = refit_bvh(*s.bvh, BvhLeafBox(leaf_box), options.bvh.threads);
    } catch (const Error&) {
        return false;  // unchanged; rebuilt instead
    }
    if (refit.rebuild_due()) return false;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    s.bvh_stats = bvh_stats(*s.bvh);
    s.pending.build_ms += ms;
    s.stats.build_ms += ms;
    ++s.stats.refits;
    ++s.pending.refits;
    detail::BackendWork work;
    if (s.backend && s.backend->refit(work)) {
        s.stats.device_bytes = s.backend->device_bytes();
        add(s.stats, work);
        add_pending(s.pending, work);
    } else {
        s.backend.reset();
        commit_backend(s, options);
    }
    return true;
}

// The backend takes the shading fields just set in s.prepared.
void update_shading(CommittedSceneState& s) {
    detail::BackendWork work;
    s.backend->update_shading(work);
    s.stats.device_bytes = s.backend->device_bytes();
    add(s.stats, work);
    add_pending(s.pending, work);
}

// The scene's features for a frame's depth (the depth only matters with mirrors or glass).
SceneFeatures features_at_depth(SceneFeatures f, bool all_features, int max_depth) {
    if (all_features) return SceneFeatures::all(max_depth);
    f.max_depth = (f.reflection || f.refraction) ? max_depth : 1;
    return f;
}

// What of a frame the preparation of a scene reads: its size, depth and samples.
FrameOptions frame_size(const FrameOptions& frame) {
    FrameOptions size;
    size.width = frame.width;
    size.height = frame.height;
    size.max_depth = frame.max_depth;
    size.samples = frame.samples;
    return size;
}

}  // namespace

void detail::check_region(const std::optional<PixelRect>& region, int width, int height) {
    if (!region) return;
    const PixelRect& r = *region;
    const auto describe = [&] {
        return "region (x " + std::to_string(r.x) + ", y " + std::to_string(r.y) + ", " + std::to_string(r.width) +
               "x" + std::to_string(r.height) + ")";
    };
    if (r.width <= 0 || r.height <= 0)
        throw Error(ErrorCode::InvalidArgument, describe() + " is empty: width and height must be positive");
    // In 64 bits: x + width must not overflow.
    if (r.x < 0 || r.y < 0 || std::int64_t{r.x} + r.width > width || std::int64_t{r.y} + r.height > height)
        throw Error(ErrorCode::InvalidArgument, describe() + " is not inside the " + std::to_string(width) + "x" +
                                                    std::to_string(height) + " frame");
}

CommittedScene detail::CommittedSceneAccess::commit(const Device& device, const Scene& scene,
                                                    const CommitOptions& options, const FrameOptions& first_frame,
                                                    std::shared_ptr<WideBvh> shared_bvh) {
    DeviceAccess::state(device, "CommittedScene::commit");  // a moved-from device has none
    auto s = std::make_shared<CommittedSceneState>(device);
    s->frame_size = frame_size(first_frame);
    s->prepared = detail::prepare_scene(scene, options, s->frame_size);
    s->digest = detail::geometry_digest(scene);
    ++s->stats.geometry_passes;
    s->scene_name = scene.name;
    s->scene_settings = scene.settings;
    commit_geometry(*s, options, std::move(shared_bvh));
    s->options = options;
    s->options.progress = nullptr;  // a frame brings its own
    s->options.tree.progress = nullptr;
    s->options.bvh.progress = nullptr;
    return make(std::move(s));
}

CommittedScene CommittedScene::commit(const Device& device, const Scene& scene, const CommitOptions& options) {
    return CommittedSceneAccess::commit(device, scene, options, FrameOptions{});
}

void CommittedScene::update(const Scene& scene, const std::function<bool(double)>& progress) {
    CommittedSceneState& s = CommittedSceneAccess::state(*this, "CommittedScene::update");
    s.forget_geometry_of();
    const detail::GeometryDigest digest = detail::geometry_digest(scene);
    // The same objects: only what shading reads changes. (An empty scene's
    // working frame follows its camera, and fewer materials than the objects
    // use is an error that preparing names: both take the long way.)
    if (s.backend && digest == s.digest && s.prepared.geometry_f.object_count() > 0 &&
        std::max<std::size_t>(scene.materials.size(), 1) >= s.prepared.material_refs) {  // none: the default one
        detail::validate_shading(scene);
        detail::PreparedShading shading = detail::prepare_shading(scene, s.options, s.frame_size, s.prepared);
        s.scene_name = scene.name;
        s.scene_settings = scene.settings;
        std::move(shading).move_into(s.prepared);
        update_shading(s);
        return;
    }
    detail::PreparedScene next = detail::prepare_scene(scene, s.options, s.frame_size);
    ++s.stats.geometry_passes;
    s.scene_name = scene.name;
    s.scene_settings = scene.settings;
    // The tree is made of the float geometry's bounds and the extent, in the working frame.
    const bool same_tree = s.backend && next.fingerprint == s.prepared.fingerprint &&
                           next.frame_origin == s.prepared.frame_origin && next.extent == s.prepared.extent &&
                           next.public_ids == s.prepared.public_ids &&
                           next.geometry_f.object_count() == s.prepared.geometry_f.object_count();
    if (same_tree && digest == s.digest) {
        // Objects as given unchanged (an empty scene whose camera moved within its frame).
        detail::PreparedShading{next.settings, next.camera, std::move(next.materials), std::move(next.lights),
                                next.features}
            .move_into(s.prepared);
        update_shading(s);
        return;
    }
    if (same_tree) {
        // Same positions, other triangle materials or normals (or double-precision
        // digits below float's): the tree still fits, the device's geometry does not.
        s.backend.reset();
        s.prepared = std::move(next);
        commit_backend(s, s.options);
        s.digest = digest;
        return;
    }
    // New geometry: a tree given for the old one (file or memory) no longer fits.
    // Objects that only moved refit a BVH; anything else builds anew.
    const bool same_objects = s.bvh && next.public_ids == s.prepared.public_ids &&
                              next.geometry_f.spheres.size() == s.prepared.geometry_f.spheres.size() &&
                              next.geometry_f.triangles.size() == s.prepared.geometry_f.triangles.size();
    // The backend is kept for a refit in place only; from here on it does
    // not match s.prepared until that succeeds, so any failure drops it.
    if (!same_objects) s.backend.reset();
    s.prepared = std::move(next);
    CommitOptions options = s.options;
    try {
        if (progress && !progress(0.0)) throw Error(ErrorCode::Cancelled, "CommittedScene::update: cancelled");
        options.tree_files.in_memory.reset();
        options.tree_files.load.reset();
        options.progress = progress;
        if (!same_objects || !refit_geometry(s, options)) {
            s.backend.reset();
            commit_geometry(s, options);
        }
    } catch (...) {
        s.backend.reset();
        s.stats.device_bytes = 0;  // nothing is kept until the scene is updated again
        throw;
    }
    options.progress = nullptr;
    if (progress) progress(1.0);
    s.options = options;
    s.digest = digest;
}

RenderResult CommittedScene::render(const FrameOptions& frame) const {
    CommittedSceneState& s = CommittedSceneAccess::state(*this, "CommittedScene::render");
    detail::check_frame_options(frame);
    s.prepared.settings = detail::frame_settings(s.scene_settings, frame, s.scene_name);
    detail::check_region(frame.region, s.prepared.settings.width, s.prepared.settings.height);
    s.prepared.features = features_at_depth(s.prepared.features, s.options.all_features, s.prepared.settings.max_depth);
    s.frame_size = frame_size(frame);
    RenderResult result = s.ready_backend().render(frame);
    // Ids leave the library as the ones Scene::add_* returned.
    if (!s.prepared.public_ids.empty())
        for (std::int32_t& id : result.ids)
            if (id >= 0) id = static_cast<std::int32_t>(s.prepared.public_id(static_cast<std::uint32_t>(id)));
    // The frame's own device work (a backend that redoes it per frame), then what commit/update left to report.
    const RenderStats& stats = result.stats;
    detail::BackendWork own;
    own.compiles = stats.compiles;
    own.geometry_uploads = stats.geometry_upload_bytes > 0 ? 1 : 0;
    own.geometry_upload_bytes = stats.geometry_upload_bytes;
    own.compile_ms = stats.compile_ms;
    own.upload_ms = stats.upload_ms;
    add(s.stats, own);
    detail::report_pending_work(s, result);
    result.stats.tree_stats = s.tree_stats;
    result.stats.bvh_stats = s.bvh_stats;
    return result;
}

void detail::report_pending_work(CommittedSceneState& s, RenderResult& result) {
    const PendingWork& p = s.pending;
    RenderStats& r = result.stats;
    r.builds += p.builds;
    r.refits += p.refits;
    r.build_ms += p.build_ms;
    r.tree_loaded = r.tree_loaded || p.tree_loaded;
    r.compiles += p.compiles;
    r.compile_ms += p.compile_ms;
    r.upload_ms += p.upload_ms;
    r.geometry_upload_bytes += p.geometry_upload_bytes;
    result.warnings.insert(result.warnings.begin(), p.warnings.begin(), p.warnings.end());
    s.pending = {};
}

const CommitStats& CommittedScene::stats() const { return CommittedSceneAccess::state(*this, "CommittedScene::stats").stats; }
const KdTree* CommittedScene::tree() const { return CommittedSceneAccess::state(*this, "CommittedScene::tree").tree.get(); }
std::optional<BvhStats> CommittedScene::bvh_stats() const {
    return CommittedSceneAccess::state(*this, "CommittedScene::bvh_stats").bvh_stats;
}
std::uint64_t CommittedScene::geometry_fingerprint() const {
    return CommittedSceneAccess::state(*this, "CommittedScene::geometry_fingerprint").prepared.fingerprint;
}
const Device& CommittedScene::device() const {
    return CommittedSceneAccess::state(*this, "CommittedScene::device").device;
}

std::uint64_t geometry_fingerprint(const Scene& scene) { return detail::prepare_scene(scene, {}).fingerprint; }

KdTree build_scene_tree(const Scene& scene, const CommitOptions& options) {
    CommitOptions kd = options;  // a kd-tree, whatever `accel` says
    kd.accel = Accel::KdTree;
    const detail::PreparedScene prepared = detail::prepare_scene(scene, kd);
    const CommitOptions o = with_build_progress(options);
    KdTree tree = build_kd_tree(prepared.build_input(), o.tree);
    if (options.traversal == Traversal::Ropes) build_ropes(tree);
    return tree;
}

}  // namespace kdrt
