// What the kernels of a built program need per work-item and work-group, as
// the OpenCL implementation reports it, and kdrt's own estimate of the
// traversal stack, which PoCL does not count as private memory.
#pragma once

#include "opencl/cl.h"
#include "opencl/kernel_variant.h"

#include <kdrt/commit_options.h>
#include <kdrt/render_stats.h>

#include <cstdint>
#include <vector>

namespace kdrt::detail::ocl {

// clGetKernelWorkGroupInfo for every kernel of `program` on `device`, sorted by name.
std::vector<KernelResources> kernel_resources(const cl::Program& program, const cl::Device& device);

// Bytes of the traversal's stack per work-item in the OpenCL kernels of
// `variant` (the arrays in cl/traverse_*.cl): entries x entry size.
std::uint64_t traversal_stack_bytes(const KernelVariant& variant);

}  // namespace kdrt::detail::ocl
