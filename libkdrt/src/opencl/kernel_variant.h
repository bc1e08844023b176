// The kernel variants of the OpenCL device: what selects a compiled program
// (the scene's effects and geometry, traversal, precision, accuracy knobs)
// and the -D options it is built with. Every program holds the renderer's
// and the ray queries' kernels.
#pragma once

#include "device/accel.h"
#include "opencl/cl_devices.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/scene_features.h>

#include <string>

namespace kdrt::detail {

// Everything that selects a compiled kernel variant.
struct KernelVariant {
    SceneFeatures features;
    Accel accel = Accel::KdTree;  // what `traversal` walks: Accel::Bvh with Stack is KDRT_TRAVERSAL_BVH
    Traversal traversal = Traversal::Stack;
    bool fp64 = false;         // the device has doubles (watertight test's fallback)
    bool normals = false;      // some triangle has shading normals
    Precision precision = Precision::Float;
    TriangleTest triangle_test = TriangleTest::Watertight;
    SphereTest sphere_test = SphereTest::Careful;
    SelfIntersection self_intersection = SelfIntersection::ScaleAware;
    double fixed_epsilon = 1e-4;
    bool mailbox = false;      // the kd-tree has an object in several leaves (set once the tree is known)
    bool cpu_device = false;   // the kernels' CPU code (cpu_kernels)
    bool exact_divide = false; // fp32 division and sqrt correctly rounded (exact_divide_sqrt)
    bool packed_leaves = false;  // the scene's buffers hold packed leaves (uses_packed_leaves)
};

KernelVariant kernel_variant(const PreparedScene& scene, const CommitOptions& options, bool device_fp64);

// Whether `device` gets the kernels' CPU code (KDRT_CPU_DEVICE, cl/common.cl):
// a CPU device with 4-wide vectors, whose compiler runs a work-group's
// work-items one after another and vectorises within each (PoCL). GPUs run
// work-items side by side and keep the plain code.
bool cpu_kernels(const ocl::ClDevice& device);

// Whether `device` can round fp32 division and square roots correctly
// (CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT). OpenCL C allows 2.5 and 3 ulp there
// by default, and NVIDIA's driver takes them: its hit distances then differed
// from the C++ twin's, and hits on shared edges changed triangle. The kernels
// are built with -cl-fp32-correctly-rounded-divide-sqrt where it can.
bool exact_divide_sqrt(const ocl::ClDevice& device);

// The same for the structure in `accel` (its BVH when it has one, as the
// cpu device traces): the BVH's traversal, or `mailbox` set for the kd-tree.
KernelVariant kernel_variant(const PreparedScene& scene, AccelRef accel, const CommitOptions& options,
                             bool device_fp64);

// Whether `variant` walks the BVH (KDRT_TRAVERSAL_BVH, cl/traverse_bvh.cl).
bool walks_bvh(const KernelVariant& variant);

// Throws kdrt::Error for what an OpenCL render cannot do with these options:
// a traversal without a structure, ropes without ropes, a BVH with another
// traversal than stack, double without fp64.
void check_opencl_request(const ocl::ClDevice& device, AccelRef accel, const CommitOptions& options);

// Whether renders and closest-hit and any-hit queries of `variant` test the leaves
// through packed leaves (KDRT_PACKED_LEAVES, cl/visit_objects.cl) when the
// scene's buffers hold them: the CPU devices' four-lane watertight test, over
// a kd-tree or a BVH.
bool uses_packed_leaves(const KernelVariant& variant);

// Rays a work-item of the persistent and query kernels takes: on a CPU
// device with the kd-tree's stack traversal or the BVH a packet of 4
// (KDRT_PACKETS, cl/traverse_packet.cl and cl/traverse_bvh_packet.cl), else 1.
unsigned rays_per_work_item(const KernelVariant& variant);

// The build options of a variant: -D options that specialise the kernels
// (code for an effect the scene does not call for is preprocessed away),
// and -cl-fp32-correctly-rounded-divide-sqrt where the device has it.
std::string kernel_options(const KernelVariant& variant);

}  // namespace kdrt::detail
