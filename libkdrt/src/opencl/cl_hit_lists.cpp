// count_hits and all_hits on OpenCL (cl/every_hit.cl): the kernel counts
// each ray's raw hits, the host prefix-sums the counts into offsets, the
// kernel writes the raw hits there, and the host sorts each ray's by (t,
// object) and drops the repeats a kd-tree's duplicated references leave (the
// same object and sphere root twice: the same t, since the same ray meets the
// same object in every leaf). Where the structure references each object once
// (the BVH, a kd-tree without duplicates, no structure), the raw hits are the
// hits and count_hits is the first pass alone.
#include "common/tsan_fork_join.h"
#include "opencl/cl_error.h"
#include "opencl/cl_query_launch.h"
#include "opencl/cl_ray_query.h"

#include <kdrt/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <string>

namespace kdrt::detail::ocl {

namespace {

// query_every_hit bound to its rays and counts; with `write`, to the offsets
// (of the launch's rays, from `base` on) and the raw hits' buffer too.
QueryKernel every_hit_kernel(const QueryTarget& target, const cl::Buffer& rays, const cl::Buffer& counts,
                             const cl::Buffer& offsets, const cl::Buffer& hits, cl_ulong base, bool write) {
    QueryKernel k = make_query_kernel(target, "query_every_hit", rays, counts);
    k.kernel.setArg(k.next_arg++, offsets);
    k.kernel.setArg(k.next_arg++, hits);
    k.kernel.setArg(k.next_arg++, base);
    k.kernel.setArg(k.next_arg++, static_cast<cl_uint>(write ? 1 : 0));
    return k;
}

// raw[i]: how many raw hits ray i has (the first pass).
void count_raw(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint32_t> raw) {
    HostQuery q;
    q.in = rays.data();
    q.in_size = sizeof(QueryRay);
    q.out = raw.data();
    q.out_size = sizeof(std::uint32_t);
    q.count = rays.size();
    q.make = [&](const cl::Buffer& in, const cl::Buffer& out) {
        return every_hit_kernel(target, in, out, cl::Buffer(), cl::Buffer(), 0, false);
    };
    run_host(target, q);
}

// The end of the batch of rays from `begin` whose raw hits fit in `budget` bytes (at least one ray).
std::size_t batch_end(std::span<const std::uint64_t> offsets, std::size_t begin, std::size_t budget) {
    const std::size_t rays = offsets.size() - 1;
    std::size_t end = begin + 1;
    while (end < rays && end - begin < (std::size_t{1} << 20) &&
           (offsets[end + 1] - offsets[begin]) * sizeof(QueryHit) <= budget)
        ++end;
    return end;
}

// Rays [begin, end)'s raw hits into raw[offsets[begin] ..] (the second pass).
void write_batch(const QueryTarget& target, std::span<const QueryRay> rays, std::span<const std::uint64_t> offsets,
                 std::size_t begin, std::size_t end, std::span<const std::uint32_t> counted, QueryHit* raw) {
    const ClDeviceContext& dev = *target.device;
    const std::size_t n = end - begin, hits = offsets[end] - offsets[begin];
    const cl_mem_flags in = CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR;
    cl::Buffer ray_buffer(dev.context(), in, n * sizeof(QueryRay), const_cast<QueryRay*>(rays.data() + begin));
    cl::Buffer offset_buffer(dev.context(), in, (n + 1) * sizeof(cl_ulong),
                             const_cast<std::uint64_t*>(offsets.data() + begin));
    cl::Buffer count_buffer(dev.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_uint));
    cl::Buffer hit_buffer(dev.context(), CL_MEM_WRITE_ONLY, std::max<std::size_t>(hits, 1) * sizeof(QueryHit));
    QueryKernel k =
        every_hit_kernel(target, ray_buffer, count_buffer, offset_buffer, hit_buffer, offsets[begin], true);
    launch_query(target, k, n);
    std::vector<std::uint32_t> written(n);
    dev.queue().enqueueReadBuffer(count_buffer, CL_TRUE, 0, n * sizeof(cl_uint), written.data());
    if (!std::equal(written.begin(), written.end(), counted.begin() + static_cast<std::ptrdiff_t>(begin)))
        throw Error(ErrorCode::Device, "the second pass of an OpenCL hit list found other hits than the first");
    if (hits > 0) dev.queue().enqueueReadBuffer(hit_buffer, CL_TRUE, 0, hits * sizeof(QueryHit), raw);
}

// Every ray's raw hits, ray i's at raw[offsets[i] .. offsets[i + 1]).
void write_raw(const QueryTarget& target, std::span<const QueryRay> rays, std::span<const std::uint32_t> counted,
               std::span<const std::uint64_t> offsets, std::vector<QueryHit>& raw) {
    const ClDevice& d = target.device->device();
    const std::size_t budget = std::min<std::uint64_t>(d.info.max_allocation, d.info.global_memory / 8);
    for (std::size_t begin = 0; begin < rays.size();) {
        const std::size_t end = batch_end(offsets, begin, budget);
        check_allocation(d, (offsets[end] - offsets[begin]) * sizeof(QueryHit),
                         "the hits of ray " + std::to_string(begin));
        write_batch(target, rays, offsets, begin, end, counted, raw.data() + offsets[begin]);
        begin = end;
    }
}

// Ray i's hits sorted nearest first (equal t: lower object, then the near
// root), repeats dropped; returns how many are left at the front.
std::uint32_t sort_ray_hits(QueryHit* first, QueryHit* last) {
    auto before = [](const QueryHit& a, const QueryHit& b) {
        if (a.t != b.t) return a.t < b.t;
        if (a.object != b.object) return a.object < b.object;
        return a.primitive < b.primitive;
    };
    std::sort(first, last, before);
    auto same = [](const QueryHit& a, const QueryHit& b) {
        return a.t == b.t && a.object == b.object && a.primitive == b.primitive;
    };
    QueryHit* end = std::unique(first, last, same);
    for (QueryHit* h = first; h != end; ++h) h->primitive = 0;  // the root's tag served; the caller names hits
    return static_cast<std::uint32_t>(end - first);
}

// Sorts every ray's raw hits in place (sort_ray_hits); counts[i]: how many ray i keeps.
void sort_raw(std::span<const std::uint64_t> offsets, std::vector<QueryHit>& raw, std::span<std::uint32_t> counts) {
    auto block = [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            counts[i] = sort_ray_hits(raw.data() + offsets[i], raw.data() + offsets[i + 1]);
    };
    TsanForkJoin tsan;
    // Isolated: the caller holds the device's lock (see parallel_copy in cl_query_launch.cpp).
    tbb::this_task_arena::isolate(
        [&] { tbb::parallel_for(tbb::blocked_range<std::size_t>(0, counts.size(), 256), tsan.task(block)); });
}

// The raw hits, sorted and without repeats: counts[i] of ray i's, and offsets for them.
void sorted_hits(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                 std::vector<std::uint64_t>& offsets, std::vector<QueryHit>& raw) {
    count_raw(target, rays, counts);
    offsets.assign(rays.size() + 1, 0);
    for (std::size_t i = 0; i < rays.size(); ++i) offsets[i + 1] = offsets[i] + counts[i];
    raw.resize(offsets.back());
    write_raw(target, rays, counts, offsets, raw);
    sort_raw(offsets, raw, counts);
}

std::string what(const QueryTarget& target) { return "OpenCL hit list on " + target.device->device().info.id; }

}  // namespace

void query_count_hits(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint32_t> counts) {
    guard_cl(what(target), [&] {
        if (!target.repeats_objects) return count_raw(target, rays, counts);
        std::vector<std::uint64_t> offsets;
        std::vector<QueryHit> raw;
        sorted_hits(target, rays, counts, offsets, raw);
    });
}

void query_all_hits(const QueryTarget& target, std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                    std::vector<QueryHit>& hits) {
    guard_cl(what(target), [&] {
        std::vector<std::uint32_t> counts(rays.size());
        std::vector<std::uint64_t> offsets;
        std::vector<QueryHit> raw;
        sorted_hits(target, rays, counts, offsets, raw);
        splits.assign(rays.size() + 1, 0);
        for (std::size_t i = 0; i < rays.size(); ++i) splits[i + 1] = splits[i] + counts[i];
        if (splits.back() == raw.size()) {
            hits = std::move(raw);
            return;
        }
        hits.resize(splits.back());
        auto place = [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i)
                std::copy_n(raw.begin() + static_cast<std::ptrdiff_t>(offsets[i]), counts[i],
                            hits.begin() + static_cast<std::ptrdiff_t>(splits[i]));
        };
        TsanForkJoin tsan;
        tbb::this_task_arena::isolate(
            [&] { tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 1024), tsan.task(place)); });
    });
}

}  // namespace kdrt::detail::ocl
