// Where queries on host arrays go on a device with memory of its own (a
// discrete GPU): two slots, each with host memory the driver has pinned
// (CL_MEM_ALLOC_HOST_PTR, mapped for the slot's life), a pair of device
// buffers and an in-order queue of its own. The host copies a piece of the
// caller's array into one slot's host memory while the other slot's piece is
// uploaded, run and read back, and DMA from pinned memory runs at the bus's
// speed, where the caller's pageable memory would go through the driver's own
// copy first. Where the device cannot pin the memory, ordinary host memory
// takes its place (slower transfers, the same results).
#pragma once

#include "opencl/cl.h"

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

namespace kdrt::detail::ocl {

class ClDeviceContext;

// A slot's host memory: pinned where the device allows, else ordinary.
class StagingMemory {
public:
    StagingMemory(const ClDeviceContext& dev, const cl::CommandQueue& queue, std::size_t bytes);
    ~StagingMemory();  // unmaps the pinned memory
    StagingMemory(const StagingMemory&) = delete;
    StagingMemory& operator=(const StagingMemory&) = delete;

    unsigned char* data() { return data_; }
    bool pinned() const { return buffer_() != nullptr; }

private:
    cl::CommandQueue queue_;
    cl::Buffer buffer_;  // the pinned buffer, or none
    std::vector<unsigned char> plain_;
    unsigned char* data_ = nullptr;
};

struct StagingSlot {
    cl::CommandQueue queue;  // slot 0: the device's queue; slot 1: a second one
    std::unique_ptr<StagingMemory> host_in, host_out;
    cl::Buffer device_in, device_out;
};

class QueryStaging {
public:
    // Bytes of input and of output each slot holds.
    static constexpr std::size_t kSlotBytes = std::size_t{8} << 20;
    static constexpr std::size_t kSlotCount = 2;

    // Allocates both slots; throws kdrt::Error(Device) when the device cannot.
    explicit QueryStaging(const ClDeviceContext& dev);

    StagingSlot& slot(std::size_t k) { return slots_[k]; }

private:
    std::array<StagingSlot, kSlotCount> slots_;
};

}  // namespace kdrt::detail::ocl
