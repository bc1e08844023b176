#include "opencl/cl_ray_query.h"

#include "common/ms_since.h"
#include "opencl/cl_error.h"

#include <kdrt/error.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <string>
#include <tuple>

namespace kdrt::detail::ocl {

namespace {

enum class Kind { Closest, Any };

const char* kernel_name(Kind kind) { return kind == Kind::Closest ? "query_closest" : "query_any"; }
std::size_t result_size(Kind kind) { return kind == Kind::Closest ? sizeof(QueryHit) : 1; }

// Launches the query kernel over [0, count) of `rays` / `out` in pieces that
// each fit in max_launch_ms at the rate measured so far. `before(first, n)`
// and `after(first, n)` run around each piece (uploads, read-backs).
template <class Before, class After>
void run_query(const QueryTarget& target, Kind kind, const cl::Buffer& rays, const cl::Buffer& out,
               std::size_t count, bool map_ids, std::size_t max_piece, Before&& before, After&& after) {
    const ClDeviceContext& dev = *target.device;
    cl::Kernel kernel(target.program, kernel_name(kind));
    cl_uint a = target.buffers->set_scene_args(kernel);
    kernel.setArg(a++, rays);
    kernel.setArg(a++, out);
    const cl_uint first_arg = a;
    a += 2;  // first, count: set per piece
    if (target.fp64) {
        const cl_double4 origin = {{target.frame_origin.x, target.frame_origin.y, target.frame_origin.z, 0.0}};
        kernel.setArg(a++, origin);
    } else {
        // hi + lo carries the origin to ~2^-48 of its size without doubles on the device.
        cl_float4 hi, lo;
        for (int i = 0; i < 3; ++i) {
            hi.s[i] = static_cast<float>(target.frame_origin[i]);
            lo.s[i] = static_cast<float>(target.frame_origin[i] - static_cast<double>(hi.s[i]));
        }
        hi.s[3] = lo.s[3] = 0.0f;
        kernel.setArg(a++, hi);
        kernel.setArg(a++, lo);
    }
    if (kind == Kind::Closest) {
        kernel.setArg(a++, target.buffers->id_map());
        kernel.setArg(a++, static_cast<cl_uint>(map_ids && target.buffers->has_id_map() ? 1 : 0));
    }
    const std::size_t local = dev.device().info.type == "gpu" ? 64 : 16;
    double rays_per_ms = 0.0;
    for (std::size_t first = 0; first < count;) {
        std::size_t n = std::min<std::size_t>(count - first, max_piece);
        if (rays_per_ms > 0.0 && target.max_launch_ms > 0.0)
            n = std::min(n, static_cast<std::size_t>(std::max(1024.0, rays_per_ms * target.max_launch_ms * 0.8)));
        else
            n = std::min<std::size_t>(n, 65536);  // a first, modest launch measures the rate
        const auto t0 = std::chrono::steady_clock::now();
        before(first, n);
        kernel.setArg(first_arg, static_cast<cl_uint>(first));
        kernel.setArg(first_arg + 1, static_cast<cl_uint>(n));
        const std::size_t items = (n + target.rays_per_item - 1) / target.rays_per_item;
        dev.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange((items + local - 1) / local * local),
                                         cl::NDRange(local));
        after(first, n);
        dev.queue().finish();
        const double ms = ms_since(t0);
        if (ms > 0.0) rays_per_ms = rays_per_ms > 0.0 ? 0.5 * (rays_per_ms + n / ms) : n / ms;
        first += n;
    }
}

// Host spans on a device that shares the host's memory: the caller's memory
// wrapped as buffers (CL_MEM_USE_HOST_PTR), which such a device may work on
// in place (PoCL does): no staging memory allocated and faulted in per call,
// no copies in and out. Mapping the results makes them the host's again, as
// the specification asks. Returns false, having traced nothing, when the
// device declines to wrap the memory (its alignment rules, read-only pages):
// the staging buffers then serve.
bool run_host_in_place(const QueryTarget& target, Kind kind, std::span<const QueryRay> rays, void* results) {
    const ClDeviceContext& dev = *target.device;
    const std::size_t out_bytes = rays.size() * result_size(kind);
    cl::Buffer ray_buffer, out_buffer;
    try {
        // The kernels only read the rays: the buffer is CL_MEM_READ_ONLY.
        ray_buffer = cl::Buffer(dev.context(), CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, rays.size_bytes(),
                                const_cast<QueryRay*>(rays.data()));
        out_buffer = cl::Buffer(dev.context(), CL_MEM_WRITE_ONLY | CL_MEM_USE_HOST_PTR, out_bytes, results);
    } catch (const cl::Error&) {
        return false;
    }
    try {
        run_query(target, kind, ray_buffer, out_buffer, rays.size(), false, rays.size(),
                  [](std::size_t, std::size_t) {}, [](std::size_t, std::size_t) {});
        void* mapped = dev.queue().enqueueMapBuffer(out_buffer, CL_TRUE, CL_MAP_READ, 0, out_bytes);
        cl::Event unmapped;
        dev.queue().enqueueUnmapMemObject(out_buffer, mapped, nullptr, &unmapped);
        unmapped.wait();
    } catch (...) {
        // Launches may still be reading and writing the caller's memory,
        // which it may free once the error reaches it.
        clFinish(dev.queue()());
        throw;
    }
    return true;
}

// Host spans: staging buffers of a bounded size, the rays written and the
// results read straight from and into the caller's memory; on a device that
// shares the host's memory, the caller's memory itself (run_host_in_place).
void run_host(const QueryTarget& target, Kind kind, std::span<const QueryRay> rays, void* results) {
    if (rays.empty()) return;
    const ClDeviceContext& dev = *target.device;
    const ClDevice& d = dev.device();
    const std::size_t per_ray = sizeof(QueryRay) + result_size(kind);
    if (d.host_memory && rays.size() <= std::numeric_limits<cl_uint>::max() &&
        std::max(rays.size_bytes(), rays.size() * result_size(kind)) <= d.info.max_allocation &&
        run_host_in_place(target, kind, rays, results))
        return;
    // At most 2^20 rays (32 MiB) per piece, and within an eighth of the device's memory.
    std::size_t piece = std::min<std::size_t>(rays.size(), std::size_t{1} << 20);
    while (piece > 1024 && (piece * sizeof(QueryRay) > d.info.max_allocation || piece * per_ray > d.info.global_memory / 8))
        piece /= 2;
    check_allocation(d, piece * sizeof(QueryRay), "the query rays");
    cl::Buffer ray_buffer(dev.context(), CL_MEM_READ_ONLY, piece * sizeof(QueryRay));
    cl::Buffer out_buffer(dev.context(), CL_MEM_WRITE_ONLY, piece * result_size(kind));
    auto* out = static_cast<unsigned char*>(results);
    std::size_t base = 0;  // the pieces of run_query index the staging buffers from 0
    try {
        for (std::size_t done = 0; done < rays.size();) {
            const std::size_t n = std::min(piece, rays.size() - done);
            base = done;
            run_query(
                target, kind, ray_buffer, out_buffer, n, false, piece,
                [&](std::size_t first, std::size_t m) {
                    dev.queue().enqueueWriteBuffer(ray_buffer, CL_FALSE, first * sizeof(QueryRay),
                                                   m * sizeof(QueryRay), rays.data() + base + first);
                },
                [&](std::size_t first, std::size_t m) {
                    dev.queue().enqueueReadBuffer(out_buffer, CL_TRUE, first * result_size(kind),
                                                  m * result_size(kind), out + (base + first) * result_size(kind));
                });
            done += n;
        }
    } catch (...) {
        clFinish(dev.queue()());  // a write may still read the caller's rays (see run_host_in_place)
        throw;
    }
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
    run_query(target, kind, ray_buffer, out_buffer, count, true, count, [](std::size_t, std::size_t) {},
              [](std::size_t, std::size_t) {});
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
