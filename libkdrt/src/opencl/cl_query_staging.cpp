#include "opencl/cl_query_staging.h"

#include "opencl/cl_device_context.h"
#include "opencl/cl_error.h"

namespace kdrt::detail::ocl {

StagingMemory::StagingMemory(const ClDeviceContext& dev, const cl::CommandQueue& queue, std::size_t bytes)
    : queue_(queue) {
    try {
        cl::Buffer b(dev.context(), CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, bytes);
        data_ = static_cast<unsigned char*>(queue_.enqueueMapBuffer(b, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, bytes));
        buffer_ = std::move(b);
    } catch (const cl::Error& e) {
        // Pinned memory refused: ordinary memory serves (slower transfers). Anything else is an error.
        const cl_int err = e.err();
        if (err != CL_MEM_OBJECT_ALLOCATION_FAILURE && err != CL_OUT_OF_RESOURCES && err != CL_OUT_OF_HOST_MEMORY)
            throw;
        plain_.resize(bytes);
        data_ = plain_.data();
    }
}

StagingMemory::~StagingMemory() {
    if (!pinned()) return;
    clEnqueueUnmapMemObject(queue_(), buffer_(), data_, 0, nullptr, nullptr);
    clFinish(queue_());
}

QueryStaging::QueryStaging(const ClDeviceContext& dev) {
    check_allocation(dev.device(), kSlotBytes, "a query's staging buffer");
    guard_cl("allocating the query staging buffers on " + dev.device().info.id, [&] {
        for (std::size_t k = 0; k < slots_.size(); ++k) {
            StagingSlot& s = slots_[k];
            s.queue = k == 0 ? dev.queue() : cl::CommandQueue(dev.context(), dev.device().device);
            s.host_in = std::make_unique<StagingMemory>(dev, s.queue, kSlotBytes);
            s.host_out = std::make_unique<StagingMemory>(dev, s.queue, kSlotBytes);
            s.device_in = cl::Buffer(dev.context(), CL_MEM_READ_ONLY, kSlotBytes);
            s.device_out = cl::Buffer(dev.context(), CL_MEM_WRITE_ONLY, kSlotBytes);
        }
    });
}

}  // namespace kdrt::detail::ocl
