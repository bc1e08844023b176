// PreparedScene: a Scene turned into what renderers work with.
//
// Everything is moved into a working frame centred on the scene's bounds, so
// the picture does not depend on where the scene sits in world space (a scene
// moved 1e5 away keeps its float precision). Geometry is flattened per object
// id in float, which the fast paths, device buffers, fingerprint and kd-tree
// builds use, and in double only for a render in double precision (a 2M-triangle
// mesh costs 88 MB in float, 168 MB more in double).
#pragma once

#include <kdrt/commit_options.h>
#include <kdrt/error.h>
#include <kdrt/frame_options.h>
#include <kdrt/kd_tree.h>
#include <kdrt/scene.h>
#include <kdrt/scene_features.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace kdrt::detail {

template <class Real>
struct SceneGeometry {
    using Vec = glm::vec<3, Real>;
    struct SphereData {
        Vec center;
        Real radius;
        std::uint32_t material;
    };
    struct TriangleData {
        // Left uninitialised, also by std::vector's resize: fill_geometry
        // writes every triangle, in parallel, and zeroing a big mesh's array
        // first was one thread's work.
        TriangleData() {}
        TriangleData(Vec a, Vec b, Vec c, std::uint32_t m, std::uint32_t n)
            : v0(a), v1(b), v2(c), material(m), normals(n) {}
        Vec v0, v1, v2;
        std::uint32_t material;
        std::uint32_t normals;  // index of 3 shading normals in `normals`, or kNoNormal
    };
    std::vector<SphereData> spheres;  // object ids 0 .. S-1
    std::vector<TriangleData> triangles;  // object ids S .. S+T-1
    std::vector<Vec> normals;

    std::uint32_t object_count() const { return static_cast<std::uint32_t>(spheres.size() + triangles.size()); }
};

struct PreparedScene {
    glm::dvec3 frame_origin{0.0};  // world position of the working frame's origin
    double extent = 1.0;           // largest side of the scene's bounds (> 0)
    Aabb bounds;                   // objects' bounds in the working frame
    Camera camera;                 // in the working frame
    RenderSettings settings;       // the scene's, with the frame's overrides applied
    std::vector<Material> materials;
    std::vector<PointLight> lights;  // in the working frame
    SceneFeatures features;
    SceneGeometry<double> geometry_d;  // filled only for AccuracyOptions::precision double
    SceneGeometry<float> geometry_f;
    bool has_double_geometry = false;
    std::uint64_t fingerprint = 0;  // XXH3-64 of the float geometry, ties kd-tree files to it
    std::size_t material_refs = 0;  // 1 + the largest material id an object uses; 0 without objects
    // Internal object id (position in SceneGeometry: spheres, then triangles)
    // -> the public id Scene::add_* returned. Empty: the identity (objects
    // added in FORMAT.md's order, the common case). Applied by the dispatch
    // layer where ids leave the library (RenderResult::ids, QueryHit::object).
    std::vector<std::uint32_t> public_ids;

    // Public object id -> geometry (scene.h): geometry_first_ids() (scene/object_ids.h).
    std::vector<std::uint32_t> geometry_first;

    std::uint32_t public_id(std::uint32_t internal) const {
        return public_ids.empty() ? internal : public_ids[internal];
    }
    // Object, geometry and primitive of every internal id in turn (3 per
    // object), for kernels that name hits themselves; empty when they are the
    // internal id, itself and 0.
    std::vector<std::uint32_t> name_table() const;
    // The public object, geometry and primitive ids of internal object `internal`.
    void name_object(std::uint32_t internal, std::uint32_t& object, std::uint32_t& geometry,
                     std::uint32_t& primitive) const;

    template <class Real>
    const SceneGeometry<Real>& geometry() const {
        if constexpr (sizeof(Real) == sizeof(double)) {
            if (!has_double_geometry)
                throw Error(ErrorCode::InvalidArgument, "internal: double geometry of a scene prepared for float");
            return geometry_d;
        } else {
            return geometry_f;
        }
    }

    // Conservative per-object bounds, computed from the float geometry and
    // padded so that they hold the double geometry too (see kBuildPadding).
    std::vector<Aabb> object_bounds() const;
    // One of them: object_bounds()[id], without the others.
    Aabb object_bound(std::uint32_t id) const;
    // The union of object_bound(id) for `ids` (any order, a BVH leaf's), padded
    // and rounded outward once: both commute with the union, so the box is the
    // same. (The geometry is finite: prepare_scene refuses scenes beyond 1e30.)
    Aabb objects_bound(std::span<const std::uint32_t> ids) const;
    // Those bounds and a perfect-split clipper for the kd-tree builders.
    KdBuildInput build_input() const;

private:
    Aabb padded(const Aabb& b) const;
};

// `scene` in the working frame, for a commit with `options`; its settings
// with `frame`'s size, depth and samples (0: the scene's).
PreparedScene prepare_scene(const Scene& scene, const CommitOptions& options, const FrameOptions& frame = {});

// The fields of a PreparedScene that shading reads and that change without
// its geometry: what CommittedScene::update() takes from a scene whose
// geometry is the prepared one's.
struct PreparedShading {
    RenderSettings settings;
    Camera camera;  // in the working frame
    std::vector<Material> materials;
    std::vector<PointLight> lights;  // in the working frame
    SceneFeatures features;

    void move_into(PreparedScene& p) &&;
};

// `scene`'s shading fields for `prepared`, which must have been prepared from
// a scene with the same objects, `options` and `frame`. Throws the kdrt::Error that
// prepare_scene() would for them (settings overrides, the camera's reach in
// float), given that the caller checked the rest: validate_shading(scene)
// (scene/scene_validation.h) and the objects' material references against
// PreparedScene::material_refs.
PreparedShading prepare_shading(const Scene& scene, const CommitOptions& options, const FrameOptions& frame,
                                const PreparedScene& prepared);

// The scene's settings with the frame's overrides (width, height, samples,
// max_depth) applied and checked; errors name the option or the scene's setting.
RenderSettings frame_settings(const RenderSettings& scene_settings, const FrameOptions& frame,
                              const std::string& scene_name);

// Throws kdrt::Error(InvalidArgument) for a frame option no frame can have
// (an enum cast from an integer that names no value). The sizes are
// frame_settings()'s, the region check_region()'s (render/committed_scene_state.h).
void check_frame_options(const FrameOptions& frame);

}  // namespace kdrt::detail
