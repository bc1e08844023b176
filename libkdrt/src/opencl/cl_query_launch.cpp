#include "opencl/cl_query_launch.h"

#include "common/ms_since.h"
#include "opencl/cl_error.h"

#include <algorithm>
#include <chrono>
#include <limits>

namespace kdrt::detail::ocl {

QueryKernel make_query_kernel(const QueryTarget& target, const char* name, const cl::Buffer& in, const cl::Buffer& out) {
    QueryKernel k;
    k.kernel = cl::Kernel(target.program, name);
    cl_uint a = target.buffers->set_scene_args(k.kernel);
    k.kernel.setArg(a++, in);
    k.kernel.setArg(a++, out);
    k.first_arg = a;
    a += 2;  // first, count: set per piece
    if (target.fp64) {
        const cl_double4 origin = {{target.frame_origin.x, target.frame_origin.y, target.frame_origin.z, 0.0}};
        k.kernel.setArg(a++, origin);
    } else {
        // hi + lo carries the origin to ~2^-48 of its size without doubles on the device.
        cl_float4 hi, lo;
        for (int i = 0; i < 3; ++i) {
            hi.s[i] = static_cast<float>(target.frame_origin[i]);
            lo.s[i] = static_cast<float>(target.frame_origin[i] - static_cast<double>(hi.s[i]));
        }
        hi.s[3] = lo.s[3] = 0.0f;
        k.kernel.setArg(a++, hi);
        k.kernel.setArg(a++, lo);
    }
    k.next_arg = a;
    return k;
}

void launch_query(const QueryTarget& target, QueryKernel& k, std::size_t count, std::size_t max_piece,
                  const std::function<void(std::size_t, std::size_t)>& before,
                  const std::function<void(std::size_t, std::size_t)>& after) {
    const ClDeviceContext& dev = *target.device;
    const std::size_t local = dev.device().info.type == "gpu" ? 64 : 16;
    double items_per_ms = 0.0;
    for (std::size_t first = 0; first < count;) {
        std::size_t n = std::min<std::size_t>(count - first, max_piece);
        if (items_per_ms > 0.0 && target.max_launch_ms > 0.0)
            n = std::min(n, static_cast<std::size_t>(std::max(1024.0, items_per_ms * target.max_launch_ms * 0.8)));
        else
            n = std::min<std::size_t>(n, 65536);  // a first, modest launch measures the rate
        const auto t0 = std::chrono::steady_clock::now();
        before(first, n);
        k.kernel.setArg(k.first_arg, static_cast<cl_uint>(first));
        k.kernel.setArg(k.first_arg + 1, static_cast<cl_uint>(n));
        const std::size_t items = (n + k.items_per_work_item - 1) / k.items_per_work_item;
        dev.queue().enqueueNDRangeKernel(k.kernel, cl::NullRange, cl::NDRange((items + local - 1) / local * local),
                                         cl::NDRange(local));
        after(first, n);
        dev.queue().finish();
        const double ms = ms_since(t0);
        if (ms > 0.0) items_per_ms = items_per_ms > 0.0 ? 0.5 * (items_per_ms + n / ms) : n / ms;
        first += n;
    }
}

namespace {

void nothing(std::size_t, std::size_t) {}

// Host memory on a device that shares the host's memory: the caller's memory
// wrapped as buffers (CL_MEM_USE_HOST_PTR), which such a device may work on
// in place (PoCL does): no staging memory allocated and faulted in per call,
// no copies in and out. Mapping the results makes them the host's again, as
// the specification asks. Returns false, having run nothing, when the
// device declines to wrap the memory (its alignment rules, read-only pages):
// the staging buffers then serve.
bool run_host_in_place(const QueryTarget& target, const HostQuery& q) {
    const ClDeviceContext& dev = *target.device;
    const std::size_t out_bytes = q.count * q.out_size;
    cl::Buffer in_buffer, out_buffer;
    try {
        // The kernels only read the input: the buffer is CL_MEM_READ_ONLY.
        in_buffer = cl::Buffer(dev.context(), CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, q.count * q.in_size,
                               const_cast<void*>(q.in));
        out_buffer = cl::Buffer(dev.context(), CL_MEM_WRITE_ONLY | CL_MEM_USE_HOST_PTR, out_bytes, q.out);
    } catch (const cl::Error&) {
        return false;
    }
    try {
        QueryKernel k = q.make(in_buffer, out_buffer);
        launch_query(target, k, q.count, q.count, nothing, nothing);
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

}  // namespace

void run_host(const QueryTarget& target, const HostQuery& q) {
    if (q.count == 0) return;
    const ClDeviceContext& dev = *target.device;
    const ClDevice& d = dev.device();
    const std::size_t per_item = q.in_size + q.out_size;
    if (d.host_memory && q.count <= std::numeric_limits<cl_uint>::max() &&
        std::max(q.count * q.in_size, q.count * q.out_size) <= d.info.max_allocation && run_host_in_place(target, q))
        return;
    // At most 2^20 items (32 MiB of rays) per piece, and within an eighth of the device's memory.
    std::size_t piece = std::min<std::size_t>(q.count, std::size_t{1} << 20);
    while (piece > 1024 &&
           (piece * std::max(q.in_size, q.out_size) > d.info.max_allocation || piece * per_item > d.info.global_memory / 8))
        piece /= 2;
    check_allocation(d, piece * q.in_size, "the query's input");
    cl::Buffer in_buffer(dev.context(), CL_MEM_READ_ONLY, piece * q.in_size);
    cl::Buffer out_buffer(dev.context(), CL_MEM_WRITE_ONLY, piece * q.out_size);
    QueryKernel k = q.make(in_buffer, out_buffer);
    const auto* in = static_cast<const unsigned char*>(q.in);
    auto* out = static_cast<unsigned char*>(q.out);
    try {
        for (std::size_t done = 0; done < q.count;) {
            const std::size_t n = std::min(piece, q.count - done);
            // The launches index the staging buffers from 0.
            launch_query(
                target, k, n, piece,
                [&](std::size_t first, std::size_t m) {
                    dev.queue().enqueueWriteBuffer(in_buffer, CL_FALSE, first * q.in_size, m * q.in_size,
                                                   in + (done + first) * q.in_size);
                },
                [&](std::size_t first, std::size_t m) {
                    dev.queue().enqueueReadBuffer(out_buffer, CL_TRUE, first * q.out_size, m * q.out_size,
                                                  out + (done + first) * q.out_size);
                });
            done += n;
        }
    } catch (...) {
        clFinish(dev.queue()());  // a write may still read the caller's input (see run_host_in_place)
        throw;
    }
}

}  // namespace kdrt::detail::ocl
