// How every query kernel of cl/ray_query.cl, cl/every_hit.cl and
// cl/closest_point.cl is launched: its arguments begin with the scene's, then
// the input and output buffers, the launch's (first, count) and the working
// frame's origin; the work goes in launches that each fit the display
// watchdog's time (QueryTarget::max_launch_ms), over buffers of the caller's
// host memory (in place where the device shares it, else staged).
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_ray_query.h"

#include <cstddef>
#include <functional>

namespace kdrt::detail::ocl {

// A query kernel with its scene, buffer and frame arguments set; (first,
// count) at first_arg and first_arg + 1 are set per launch, and the kernel's
// own arguments from next_arg on by its caller.
struct QueryKernel {
    cl::Kernel kernel;
    cl_uint first_arg = 0;
    cl_uint next_arg = 0;
    unsigned items_per_work_item = 1;  // query_closest and query_any: QueryTarget::rays_per_item
};

QueryKernel make_query_kernel(const QueryTarget& target, const char* name, const cl::Buffer& in, const cl::Buffer& out);

// Launches the kernel over items [0, count) on the device's queue, in
// pieces that each fit in max_launch_ms at the rate measured so far (0 or
// less: one launch). Returns with the work finished.
void launch_query(const QueryTarget& target, QueryKernel& k, std::size_t count);

// A query over `count` items of host memory: in_size bytes of input and
// out_size bytes of output each; make(in, out) binds the kernel to the
// buffers holding them.
struct HostQuery {
    const void* in = nullptr;
    std::size_t in_size = 0;
    void* out = nullptr;
    std::size_t out_size = 0;
    std::size_t count = 0;
    std::function<QueryKernel(const cl::Buffer& in, const cl::Buffer& out)> make;
};

// Runs it on the caller's memory where the device shares the host's, else
// through the device's staging slots (cl_query_staging.h), a piece in each
// at a time; an item larger than a slot is kdrt::Error(InvalidArgument). The
// caller holds the device's lock.
void run_host(const QueryTarget& target, const HostQuery& q);

}  // namespace kdrt::detail::ocl
