// The kernel variants of the OpenCL device: what selects a compiled program
// (the scene's effects and geometry, traversal, precision, accuracy knobs)
// and the -D options it is built with. Every program holds the renderer's
// and the ray queries' kernels.
#pragma once

#include "opencl/cl_devices.h"
#include "scene/prepared_scene.h"

#include <kdrt/render_options.h>

#include <string>

namespace kdrt::detail {

// Everything that selects a compiled kernel variant.
struct KernelVariant {
    SceneFeatures features;
    Traversal traversal = Traversal::Stack;
    bool fp64 = false;         // the device has doubles (watertight test's fallback)
    bool normals = false;      // some triangle has shading normals
    Precision precision = Precision::Float;
    TriangleTest triangle_test = TriangleTest::Watertight;
    SphereTest sphere_test = SphereTest::Careful;
    SelfIntersection self_intersection = SelfIntersection::ScaleAware;
    double fixed_epsilon = 1e-4;
    bool mailbox = false;      // the tree has an object in several leaves (set once the tree is known)
    unsigned leaf_lanes = 0;   // triangles a leaf test takes at once (4, or 0: one at a time)
};

KernelVariant kernel_variant(const PreparedScene& scene, const RenderOptions& options, bool device_fp64);

// How many triangles the kernels' leaf test takes at once on `device`
// (KDRT_LEAF_LANES, cl/visit_objects.cl): 4 on a CPU device with 4-wide
// vectors, whose compiler vectorises within a work-item rather than across
// them; 0 (one at a time) on GPUs.
unsigned leaf_lanes(const ocl::ClDevice& device);

// The same with `mailbox` set for `tree` (null: none).
KernelVariant kernel_variant(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options,
                             bool device_fp64);

// Throws kdrt::Error for what an OpenCL render cannot do with these options:
// a traversal without a tree, ropes without ropes, double without fp64.
void check_opencl_request(const ocl::ClDevice& device, const KdTree* tree, const RenderOptions& options);

// The -D options that specialise the kernels for a variant: code for an
// effect the scene does not call for is preprocessed away.
std::string kernel_options(const KernelVariant& variant);

}  // namespace kdrt::detail
