#include "opencl/cl_ray_query.h"

#include "opencl/cl_error.h"
#include "opencl/cl_query_launch.h"

#include <kdrt/error.h>

#include <limits>
#include <string>
#include <tuple>

namespace kdrt::detail::ocl {

namespace {

enum class Kind { Closest, Any };

const char* kernel_name(Kind kind) { return kind == Kind::Closest ? "query_closest" : "query_any"; }
std::size_t result_size(Kind kind) { return kind == Kind::Closest ? sizeof(QueryHit) : 1; }

// query_closest / query_any bound to `rays` and `out`; closest hits carry the
// application's ids with map_ids where the buffers have an id map.
QueryKernel ray_query_kernel(const QueryTarget& target, Kind kind, const cl::Buffer& rays, const cl::Buffer& out,
                             bool map_ids) {
    QueryKernel k = make_query_kernel(target, kernel_name(kind), rays, out);
    k.items_per_work_item = target.rays_per_item;
    if (kind == Kind::Closest) {
        k.kernel.setArg(k.next_arg++, target.buffers->id_map());
        k.kernel.setArg(k.next_arg++, static_cast<cl_uint>(map_ids && target.buffers->has_id_map() ? 1 : 0));
    }
    return k;
}

void run_host(const QueryTarget& target, Kind kind, std::span<const QueryRay> rays, void* results) {
    HostQuery q;
    q.in = rays.data();
    q.in_size = sizeof(QueryRay);
    q.out = results;
    q.out_size = result_size(kind);
    q.count = rays.size();
    q.make = [&](const cl::Buffer& in, const cl::Buffer& out) { return ray_query_kernel(target, kind, in, out, false); };
    ocl::run_host(target, q);
}

// The application's buffer `mem`: in the device's context, large enough,
// and accessible the way the kernel uses it.
cl::Buffer checked_buffer(const ClDeviceContext& dev, cl_mem mem, std::size_t bytes, const char* what, bool written) {
    const std::string name = std::string("the ") + what + " buffer";
    if (mem == nullptr) throw Error(ErrorCode::InvalidArgument, name + " is a null cl_mem");
    cl_context context = nullptr;
    cl_mem_object_type type = 0;
    std::size_t size = 0;
    cl_mem_flags flags = 0;
    for (auto [info, size_of, out] :
         {std::tuple<cl_mem_info, std::size_t, void*>{CL_MEM_CONTEXT, sizeof context, &context},
          {CL_MEM_TYPE, sizeof type, &type}, {CL_MEM_SIZE, sizeof size, &size}, {CL_MEM_FLAGS, sizeof flags, &flags}})
        if (cl_int err = clGetMemObjectInfo(mem, info, size_of, out, nullptr); err != CL_SUCCESS)
            throw Error(ErrorCode::InvalidArgument, name + " cannot be queried (clGetMemObjectInfo: " +
                                                        cl_error_name(err) + "); is it a valid cl_mem?");
    if (context != dev.context()())
        throw Error(ErrorCode::InvalidArgument, name + " belongs to another OpenCL context than the scene's device (" +
                                                    dev.device().info.name + "); create it on the context given to "
                                                    "wrap_opencl_device");
    if (type != CL_MEM_OBJECT_BUFFER) throw Error(ErrorCode::InvalidArgument, name + " is not a buffer (an image?)");
    if (size < bytes)
        throw Error(ErrorCode::InvalidArgument, name + " holds " + std::to_string(size) + " bytes but the query needs " +
                                                    std::to_string(bytes));
    if (written && (flags & CL_MEM_READ_ONLY) != 0)
        throw Error(ErrorCode::InvalidArgument, name + " is CL_MEM_READ_ONLY but receives the results");
    if (!written && (flags & CL_MEM_WRITE_ONLY) != 0)
        throw Error(ErrorCode::InvalidArgument, name + " is CL_MEM_WRITE_ONLY but the kernels read it");
    return cl::Buffer(mem, true);
}

void run_buffers(const QueryTarget& target, Kind kind, cl_mem rays, cl_mem out, std::size_t count) {
    if (count > std::numeric_limits<cl_uint>::max())
        throw Error(ErrorCode::InvalidArgument, "a ray query takes at most 2^32-1 rays per call, not " +
                                                    std::to_string(count));
    const ClDeviceContext& dev = *target.device;
    const char* out_name = kind == Kind::Closest ? "hits" : "occluded";
    const cl::Buffer ray_buffer = checked_buffer(dev, rays, count * sizeof(QueryRay), "rays", false);
    const cl::Buffer out_buffer = checked_buffer(dev, out, count * result_size(kind), out_name, true);
    if (count == 0) return;
    QueryKernel k = ray_query_kernel(target, kind, ray_buffer, out_buffer, true);
    launch_query(target, k, count);
}

std::string what(const QueryTarget& target) { return "OpenCL ray query on " + target.device->device().info.id; }

}  // namespace

void query_closest(const QueryTarget& target, std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    if (hits.size() != rays.size())
        throw Error(ErrorCode::InvalidArgument, "intersect: " + std::to_string(rays.size()) + " rays but " +
                                                    std::to_string(hits.size()) + " hits");
    guard_cl(what(target), [&] { run_host(target, Kind::Closest, rays, hits.data()); });
}

void query_any(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) {
    if (occluded.size() != rays.size())
        throw Error(ErrorCode::InvalidArgument, "occluded: " + std::to_string(rays.size()) + " rays but " +
                                                    std::to_string(occluded.size()) + " results");
    guard_cl(what(target), [&] { run_host(target, Kind::Any, rays, occluded.data()); });
}

void query_closest(const QueryTarget& target, cl_mem rays, cl_mem hits, std::size_t count) {
    guard_cl(what(target), [&] { run_buffers(target, Kind::Closest, rays, hits, count); });
}

void query_any(const QueryTarget& target, cl_mem rays, cl_mem occluded, std::size_t count) {
    guard_cl(what(target), [&] { run_buffers(target, Kind::Any, rays, occluded, count); });
}

}  // namespace kdrt::detail::ocl
