// The OpenCL renderer: the same picture as the C++ reference, traced by the
// kernels in cl/ as a wavefront of ray queues.
#pragma once

#include "opencl/cl_devices.h"
#include "render/prepared_scene.h"

#include <kdrt/render.h>

#include <string>

namespace kdrt::detail {

// The -D options that specialise the kernels for a scene's features.
std::string kernel_options(const SceneFeatures& features, Traversal traversal, bool fp64, bool has_normals);

RenderResult render_opencl(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options,
                           const ocl::ClDevice& device);

}  // namespace kdrt::detail
