// Where queries on host arrays go on a device with memory of its own (a
// discrete GPU): two slots, each with pinned host memory (CL_MEM_ALLOC_HOST_PTR,
// mapped for the slot's life), a pair of device buffers and an in-order queue
// of its own. The host copies a piece of the caller's array into one slot's
// pinned memory while the other slot's piece is uploaded, run and read back,
// and DMA from pinned memory runs at the bus's speed, where the caller's
// pageable memory would go through the driver's own copy first.
#pragma once

#include "opencl/cl.h"

#include <array>
#include <cstddef>

namespace kdrt::detail::ocl {

class ClDeviceContext;

struct StagingSlot {
    cl::CommandQueue queue;            // slot 0: the device's queue; slot 1: a second one
    cl::Buffer pinned_in, pinned_out;  // host memory the driver has pinned
    unsigned char* host_in = nullptr;  // their mapped addresses
    unsigned char* host_out = nullptr;
    cl::Buffer device_in, device_out;
};

class QueryStaging {
public:
    // Bytes of input and of output each slot holds.
    static constexpr std::size_t kSlotBytes = std::size_t{8} << 20;

    // Allocates and maps both slots; throws kdrt::Error(Device) when the device cannot.
    explicit QueryStaging(const ClDeviceContext& dev);
    ~QueryStaging();  // unmaps the pinned memory
    QueryStaging(const QueryStaging&) = delete;
    QueryStaging& operator=(const QueryStaging&) = delete;

    StagingSlot& slot(std::size_t k) { return slots_[k]; }
    static constexpr std::size_t slot_count() { return 2; }

private:
    std::array<StagingSlot, 2> slots_;
};

}  // namespace kdrt::detail::ocl
