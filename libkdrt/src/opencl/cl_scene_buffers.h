// A committed scene's buffers on an OpenCL device: the geometry and the
// kd-tree or the BVH, uploaded once per geometry, and the small shading buffers
// (materials, lights, scene constants), uploaded again on their own when the
// lights or materials change. Frames and ray queries run on these.
#pragma once

#include "device/accel.h"
#include "device/kernel_records.h"
#include "opencl/cl.h"
#include "opencl/cl_device_context.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>

#include <kdrt/commit_options.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace kdrt::detail::ocl {

class ClSceneBuffers {
public:
    // Uploads the geometry in `precision` (the scene must hold it), the
    // structure (none for Traversal::None): the BVH's nodes and leaf lists as
    // they are where accel has a BVH, else the kd-tree with its ropes if it
    // has them; then the shading buffers. The caller holds the device's lock. Returns the
    // bytes uploaded. `progress` (may be empty) hears the finished fraction
    // after each buffer; false cancels with kdrt::Error(Cancelled).
    std::uint64_t upload_geometry(const ClDeviceContext& device, const PreparedScene& scene, AccelRef accel,
                                  Precision precision, const std::function<bool(double)>& progress = {});

    // Materials, lights and the scene constants (background, ambient, light
    // count) again, for a scene whose geometry did not change. Returns the
    // bytes uploaded. The caller holds the device's lock.
    std::uint64_t upload_shading(const ClDeviceContext& device, const PreparedScene& scene);

    // The table internal object id -> the application's id, for ray queries
    // into the application's buffers; empty: the ids are the identity.
    void upload_id_map(const ClDeviceContext& device, const std::vector<std::uint32_t>& public_ids);

    // Sets the KDRT_SCENE_PARAMS arguments (cl/render.cl) as kernel
    // arguments 0..13; returns the index of the next argument.
    cl_uint set_scene_args(cl::Kernel& kernel) const;

    bool uploaded() const { return uploaded_; }
    // Whether the structure's leaves were uploaded packed too (a CPU device,
    // a small structure with triangles: plan_leaf_blocks), for uses_packed_leaves.
    bool leaves_packed() const { return leaves_packed_; }
    Precision precision() const { return precision_; }
    bool has_id_map() const { return has_id_map_; }
    const cl::Buffer& id_map() const { return id_map_; }  // one dummy element without a map
    std::uint64_t device_bytes() const { return geometry_bytes_ + shading_bytes_; }

private:
    template <class Real>
    void upload_geometry_in(const ClDeviceContext& device, const PreparedScene& scene, AccelRef accel,
                            const std::function<bool(double)>& progress);
    template <class Real>
    void upload_packed_leaves(const ClDeviceContext& device, const PreparedScene& scene, AccelRef accel);
    template <class Real>
    void upload_shading_in(const ClDeviceContext& device, const PreparedScene& scene);

    bool uploaded_ = false;
    bool leaves_packed_ = false;
    Precision precision_ = Precision::Float;
    cl::Buffer spheres_, triangles_, normals_, nodes_, leaf_objects_, ropes_;
    cl::Buffer bvh_nodes_;  // one dummy element with a kd-tree, as nodes_ and ropes_ have with a BVH
    // One dummy element each when not packed; packed_bvh_nodes_ also with a kd-tree.
    cl::Buffer packed_bvh_nodes_, packed_leaves_, leaf_blocks_, leaf_spheres_;
    cl::Buffer materials_, lights_;
    cl::Buffer id_map_;
    bool has_id_map_ = false;
    GpuSceneInfo info_{};
    std::uint64_t geometry_bytes_ = 0, shading_bytes_ = 0;
};

}  // namespace kdrt::detail::ocl
