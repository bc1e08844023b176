#include "opencl/kernel_variant.h"

#include "cpu/mailbox.h"
#include "device/kernel_records.h"

#include <kdrt/error.h>

#include <cstdio>

namespace kdrt::detail {

KernelVariant kernel_variant(const PreparedScene& scene, const CommitOptions& options, bool device_fp64) {
    KernelVariant v;
    v.features = scene.features;
    v.traversal = options.traversal;
    v.fp64 = device_fp64;
    v.normals = !scene.geometry_f.normals.empty();  // the same in both precisions
    v.precision = options.accuracy.precision;
    v.triangle_test = options.accuracy.triangle_test;
    v.sphere_test = options.accuracy.sphere_test;
    v.self_intersection = options.accuracy.self_intersection;
    v.fixed_epsilon = options.accuracy.fixed_epsilon;
    return v;
}

bool uses_packed_leaves(const KernelVariant& v) {
    return v.cpu_device && v.features.triangles && v.triangle_test == TriangleTest::Watertight &&
           v.traversal != Traversal::None;
}

bool walks_bvh(const KernelVariant& v) { return v.accel == Accel::Bvh && v.traversal == Traversal::Stack; }

unsigned rays_per_work_item(const KernelVariant& v) {
    return v.cpu_device && v.traversal == Traversal::Stack ? 4 : 1;
}

std::string kernel_options(const KernelVariant& v) {
    const SceneFeatures& f = v.features;
    const int traversal = walks_bvh(v) ? KDRT_TRAVERSAL_BVH : static_cast<int>(v.traversal);
    std::string o = "-DKDRT_TRAVERSAL=" + std::to_string(traversal);
    if (f.spheres) o += " -DKDRT_HAS_SPHERES";
    if (f.triangles) o += " -DKDRT_HAS_TRIANGLES";
    if (f.triangles && v.normals) o += " -DKDRT_HAS_NORMALS";
    if (f.lights) o += " -DKDRT_HAS_LIGHTS";
    if (f.max_depth > 1 && f.reflection) o += " -DKDRT_HAS_REFLECTION";
    if (f.max_depth > 1 && f.refraction) o += " -DKDRT_HAS_REFRACTION";
    o += " -DKDRT_MAX_DEPTH=" + std::to_string(f.max_depth);
    if (v.fp64) o += " -DKDRT_HAS_FP64";
    if (v.precision == Precision::Double) o += " -DKDRT_DOUBLE";
    if (v.mailbox) o += " -DKDRT_MAILBOX";
    if (v.cpu_device) o += " -DKDRT_CPU_DEVICE";
    if (v.packed_leaves && uses_packed_leaves(v)) o += " -DKDRT_PACKED_LEAVES";
    if (rays_per_work_item(v) > 1) o += " -DKDRT_PACKETS=" + std::to_string(rays_per_work_item(v));
    if (v.exact_divide) o += " -cl-fp32-correctly-rounded-divide-sqrt";
    if (v.triangle_test == TriangleTest::MollerTrumbore) o += " -DKDRT_MOLLER_TRUMBORE";
    if (v.sphere_test == SphereTest::Textbook) o += " -DKDRT_TEXTBOOK_SPHERE";
    if (v.self_intersection == SelfIntersection::FixedEpsilon) {
        char eps[64];
        std::snprintf(eps, sizeof eps, " -DKDRT_FIXED_EPSILON=%.17g", v.fixed_epsilon);
        o += eps;
    }
    return o;
}

static_assert(static_cast<int>(Traversal::None) == 0 && static_cast<int>(Traversal::Restart) == 1 &&
                  static_cast<int>(Traversal::Ropes) == 2 && static_cast<int>(Traversal::Stack) == 3 &&
                  static_cast<int>(Traversal::ShortStack) == 4,
              "KDRT_TRAVERSAL numbers in cl/common.cl");
static_assert(KDRT_TRAVERSAL_BVH > static_cast<int>(Traversal::ShortStack), "KDRT_TRAVERSAL_BVH is none of Traversal's");

void check_opencl_request(const ocl::ClDevice& device, AccelRef accel, const CommitOptions& options) {
    if (accel.bvh) {
        if (!bvh_has_traversal(options.traversal))
            throw Error(ErrorCode::InvalidArgument, std::string("the BVH has no ") + to_string(options.traversal) +
                                                        " traversal: only stack (and none)");
        if (accel.bvh->nodes.empty()) throw Error(ErrorCode::InvalidArgument, "the BVH has no root node");
    } else {
        if (options.traversal != Traversal::None && !accel.kd)
            throw Error(ErrorCode::InvalidArgument, "traversal needs a kd-tree");
        if (options.traversal == Traversal::Ropes && !accel.kd->has_ropes())
            throw Error(ErrorCode::InvalidArgument, "the ropes traversal needs a kd-tree with ropes");
    }
    if (options.accuracy.precision == Precision::Double && !device.info.fp64)
        throw Error(ErrorCode::Unsupported, "--precision double needs a device with fp64; " + device.info.id + " (" +
                                                device.info.name + ") has none");
}

bool cpu_kernels(const ocl::ClDevice& device) {
    if (device.info.type != "cpu") return false;
    try {
        return device.device.getInfo<CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT>() >= 4;
    } catch (const cl::Error&) {
        return false;  // a device that cannot say keeps the plain code
    }
}

bool exact_divide_sqrt(const ocl::ClDevice& device) {
    try {
        return (device.device.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
    } catch (const cl::Error&) {
        return false;
    }
}

KernelVariant kernel_variant(const PreparedScene& scene, AccelRef accel, const CommitOptions& options,
                             bool device_fp64) {
    KernelVariant v = kernel_variant(scene, options, device_fp64);
    if (accel.bvh) v.accel = Accel::Bvh;  // every object in one leaf: no mailbox
    else v.mailbox = options.traversal != Traversal::None && tree_duplicates_objects(accel.kd);
    return v;
}

}  // namespace kdrt::detail
