// The OpenCL renderer: the same picture as the C++ reference, traced by the
// kernels in cl/ as a wavefront of ray queues.
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
};

KernelVariant kernel_variant(const PreparedScene& scene, const RenderOptions& options, bool device_fp64);

// The -D options that specialise the kernels for a variant: code for an
// effect the scene does not call for is preprocessed away.
std::string kernel_options(const KernelVariant& variant);

RenderResult render_opencl(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options,
                           const ocl::ClDevice& device);

}  // namespace kdrt::detail
