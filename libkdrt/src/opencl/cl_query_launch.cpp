#include "opencl/cl_query_launch.h"

#include "common/ms_since.h"
#include "common/parallel_chunks.h"
#include "opencl/cl_error.h"
#include "opencl/cl_query_staging.h"

#include <kdrt/error.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

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

namespace {

std::size_t local_size(const ClDeviceContext& dev) { return dev.device().info.type == "gpu" ? 64 : 16; }

// One launch of k over items [first, first + n) on `queue`.
void enqueue_launch(const cl::CommandQueue& queue, QueryKernel& k, std::size_t first, std::size_t n, std::size_t local) {
    k.kernel.setArg(k.first_arg, static_cast<cl_uint>(first));
    k.kernel.setArg(k.first_arg + 1, static_cast<cl_uint>(n));
    const std::size_t items = (n + k.items_per_work_item - 1) / k.items_per_work_item;
    queue.enqueueNDRangeKernel(k.kernel, cl::NullRange, cl::NDRange((items + local - 1) / local * local),
                               cl::NDRange(local));
}

// How many items the next launch takes: at most `most`, and within the
// target's max_launch_ms at the rate measured so far (items per ms; 0: none
// yet, so a modest first launch measures it).
std::size_t launch_items(const QueryTarget& target, double items_per_ms, std::size_t most) {
    if (target.max_launch_ms <= 0.0) return most;
    if (items_per_ms <= 0.0) return std::min<std::size_t>(most, 65536);
    return std::min(most, static_cast<std::size_t>(std::max(1024.0, items_per_ms * target.max_launch_ms * 0.8)));
}

void update_rate(double& items_per_ms, std::size_t n, double ms) {
    if (ms > 0.0) items_per_ms = items_per_ms > 0.0 ? 0.5 * (items_per_ms + n / ms) : n / ms;
}

}  // namespace

void launch_query(const QueryTarget& target, QueryKernel& k, std::size_t count) {
    const ClDeviceContext& dev = *target.device;
    double items_per_ms = 0.0;
    for (std::size_t first = 0; first < count;) {
        const std::size_t n = launch_items(target, items_per_ms, count - first);
        const auto t0 = std::chrono::steady_clock::now();
        enqueue_launch(dev.queue(), k, first, n, local_size(dev));
        dev.queue().finish();
        update_rate(items_per_ms, n, ms_since(t0));
        first += n;
    }
}

namespace {

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
        launch_query(target, k, q.count);
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

// The bytes [0, bytes) of src into dst, on several threads: a slot's piece
// is megabytes, which one core copies slower than the bus carries them.
// Isolated: the caller holds the device's lock, and a thread waiting here
// must not take up another task of the application's that asks for it.
void parallel_copy(unsigned char* dst, const unsigned char* src, std::size_t bytes) {
    tbb::this_task_arena::isolate([&] {
        for_each_chunk(
            bytes, [&](std::size_t, std::size_t b, std::size_t e) { std::memcpy(dst + b, src + b, e - b); },
            std::size_t{1} << 20);
    });
}

// A piece of the query in a staging slot: items [first, first + n), since `started`.
struct PieceInFlight {
    std::size_t first = 0, n = 0;
    std::chrono::steady_clock::time_point started;
    cl::Event read;
};

// Host memory on a device with memory of its own, through the two slots of
// QueryStaging in turn: while one slot's piece is on the device, the host
// empties the other's results and fills it with the next piece. Each piece is
// one launch within max_launch_ms at the rate measured so far; a piece's time
// counts from its copy in to its results' collection, transfers and waits
// included, so pieces err on the short side.
void run_host_staged(const QueryTarget& target, const HostQuery& q) {
    const ClDeviceContext& dev = *target.device;
    const std::size_t item_bytes = std::max(q.in_size, q.out_size);
    if (item_bytes == 0 || item_bytes > QueryStaging::kSlotBytes)
        throw Error(ErrorCode::InvalidArgument, "a query item of " + std::to_string(item_bytes) +
                                                    " bytes does not fit the OpenCL staging slots");
    QueryStaging& staging = dev.query_staging();
    const std::size_t capacity = QueryStaging::kSlotBytes / item_bytes;
    std::array<QueryKernel, QueryStaging::kSlotCount> kernels;
    std::array<std::optional<PieceInFlight>, QueryStaging::kSlotCount> pieces;
    for (std::size_t k = 0; k < kernels.size(); ++k)
        kernels[k] = q.make(staging.slot(k).device_in, staging.slot(k).device_out);
    const auto* in = static_cast<const unsigned char*>(q.in);
    auto* out = static_cast<unsigned char*>(q.out);
    const std::size_t local = local_size(dev);
    double items_per_ms = 0.0;
    try {
        dev.queue().finish();  // the scene's uploads, on the device's queue, before slot 1's queue runs
        std::size_t next = 0;
        auto in_flight = [&] { return std::ranges::any_of(pieces, [](const auto& p) { return p.has_value(); }); };
        for (std::size_t k = 0; next < q.count || in_flight(); k = (k + 1) % pieces.size()) {
            StagingSlot& slot = staging.slot(k);
            if (std::optional<PieceInFlight>& p = pieces[k]) {
                p->read.wait();
                parallel_copy(out + p->first * q.out_size, slot.host_out->data(), p->n * q.out_size);
                update_rate(items_per_ms, p->n, ms_since(p->started));
                p.reset();
            }
            if (next == q.count) continue;
            PieceInFlight p;
            p.first = next;
            p.n = launch_items(target, items_per_ms, std::min(capacity, q.count - next));
            p.started = std::chrono::steady_clock::now();
            parallel_copy(slot.host_in->data(), in + p.first * q.in_size, p.n * q.in_size);
            slot.queue.enqueueWriteBuffer(slot.device_in, CL_FALSE, 0, p.n * q.in_size, slot.host_in->data());
            enqueue_launch(slot.queue, kernels[k], 0, p.n, local);
            slot.queue.enqueueReadBuffer(slot.device_out, CL_FALSE, 0, p.n * q.out_size, slot.host_out->data(), nullptr,
                                         &p.read);
            slot.queue.flush();
            next += p.n;
            pieces[k] = std::move(p);
        }
    } catch (...) {
        // The slots are idle again before the next query uses them.
        for (std::size_t k = 0; k < pieces.size(); ++k) clFinish(staging.slot(k).queue());
        throw;
    }
}

}  // namespace

void run_host(const QueryTarget& target, const HostQuery& q) {
    if (q.count == 0) return;
    const ClDevice& d = target.device->device();
    if (d.host_memory && q.count <= std::numeric_limits<cl_uint>::max() &&
        std::max(q.count * q.in_size, q.count * q.out_size) <= d.info.max_allocation && run_host_in_place(target, q))
        return;
    run_host_staged(target, q);
}

}  // namespace kdrt::detail::ocl
