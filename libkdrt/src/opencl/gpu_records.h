// The buffer records (device/kernel_records.h) of each working precision, and the
// conversion of a vector into a record's float[3] / double[3].
#pragma once

#include "bvh/bvh.h"
#include "device/kernel_records.h"

#include <cstddef>

namespace kdrt::detail::ocl {

// The BVH's nodes go to CPU devices as they are: GpuBvhNode is WideBvhNode's bytes
// (GPUs get them slot by slot, GpuBvhSlot; cl_scene_buffers.cpp).
static_assert(KDRT_BVH_WIDTH == kWideBvhWidth && KDRT_BVH_LEAF_FLAG == kBvhLeafFlag &&
                  KDRT_BVH_MAX_DEPTH == kBvhMaxDepth,
              "the BVH's constants in kernel_records.h");
static_assert(sizeof(GpuBvhNode) == sizeof(WideBvhNode) && offsetof(GpuBvhNode, box) == offsetof(WideBvhNode, box) &&
                  offsetof(GpuBvhNode, child) == offsetof(WideBvhNode, child) &&
                  offsetof(GpuBvhNode, count) == offsetof(WideBvhNode, count),
              "GpuBvhNode must have WideBvhNode's layout");

template <class Real>
struct GpuRecords;
template <>
struct GpuRecords<float> {
    using Sphere = GpuSphere;
    using Triangle = GpuTriangle;
    using QueuedRay = GpuRay;
    using Camera = GpuCamera;
    using Light = GpuLight;
    using LeafBlock = GpuLeafBlock;
};
template <>
struct GpuRecords<double> {
    using Sphere = GpuSphereD;
    using Triangle = GpuTriangleD;
    using QueuedRay = GpuRayD;
    using Camera = GpuCameraD;
    using Light = GpuLightD;
    using LeafBlock = GpuLeafBlockD;
};

template <class T, class V>
void put3(T* dst, const V& v) {
    dst[0] = static_cast<T>(v.x);
    dst[1] = static_cast<T>(v.y);
    dst[2] = static_cast<T>(v.z);
}

}  // namespace kdrt::detail::ocl
