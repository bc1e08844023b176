#include "opencl/cl_query_staging.h"

#include "opencl/cl_device_context.h"
#include "opencl/cl_error.h"

namespace kdrt::detail::ocl {

namespace {

// A pinned buffer and its address, mapped on the slot's queue until the staging goes.
cl::Buffer pinned(const ClDeviceContext& dev, const cl::CommandQueue& queue, unsigned char*& address) {
    cl::Buffer b(dev.context(), CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, QueryStaging::kSlotBytes);
    address = static_cast<unsigned char*>(
        queue.enqueueMapBuffer(b, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, QueryStaging::kSlotBytes));
    return b;
}

}  // namespace

QueryStaging::QueryStaging(const ClDeviceContext& dev) {
    check_allocation(dev.device(), kSlotBytes, "a query's staging buffer");
    guard_cl("allocating the query staging buffers on " + dev.device().info.id, [&] {
        for (std::size_t k = 0; k < slots_.size(); ++k) {
            StagingSlot& s = slots_[k];
            s.queue = k == 0 ? dev.queue() : cl::CommandQueue(dev.context(), dev.device().device);
            s.pinned_in = pinned(dev, s.queue, s.host_in);
            s.pinned_out = pinned(dev, s.queue, s.host_out);
            s.device_in = cl::Buffer(dev.context(), CL_MEM_READ_ONLY, kSlotBytes);
            s.device_out = cl::Buffer(dev.context(), CL_MEM_WRITE_ONLY, kSlotBytes);
        }
    });
}

QueryStaging::~QueryStaging() {
    for (StagingSlot& s : slots_) {
        if (!s.queue()) continue;
        if (s.host_in) clEnqueueUnmapMemObject(s.queue(), s.pinned_in(), s.host_in, 0, nullptr, nullptr);
        if (s.host_out) clEnqueueUnmapMemObject(s.queue(), s.pinned_out(), s.host_out, 0, nullptr, nullptr);
        clFinish(s.queue());
    }
}

}  // namespace kdrt::detail::ocl
