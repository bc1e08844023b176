// The OpenCL side of a kdrt::Device: one context, one in-order command queue
// and the programs built on them, made once and kept for the device's life,
// so a frame or a ray query pays for none of them again; on a device with
// memory of its own also the staging of host-array queries, with a second
// queue (cl_query_staging.h), made at the first such query.
//
// Thread safety: everything that enqueues work on the queue, or builds a
// program, holds lock() for its whole sequence of calls (the queue is shared
// by every scene committed on the device, and OpenCL kernels' arguments are
// per-object state).
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_devices.h"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace kdrt::detail::ocl {

class QueryStaging;

// A program for one kernel-options key, and what getting it cost.
struct ProgramHandle {
    cl::Program program;
    bool compiled_now = false;  // built from source or loaded from the disk cache by this call
    bool cache_hit = false;     // loaded from the disk kernel cache (by this call or when first built)
    double compile_ms = 0.0;    // (when compiled_now) the time it took
    std::vector<std::string> warnings;  // disk kernel cache problems, when compiled_now
};

class ClDeviceContext {
public:
    // A context and an in-order queue of kdrt's own on `device`.
    explicit ClDeviceContext(const ClDevice& device);

    // The application's objects, retained (released with this object). Checks
    // that the queue belongs to the context and the device, that the device
    // is in the context, and that it runs OpenCL C 1.2 kernels with a
    // compiler; throws kdrt::Error(Device) saying which check failed.
    ClDeviceContext(cl_context context, cl_device_id device, cl_command_queue queue);

    ClDeviceContext(const ClDeviceContext&) = delete;
    ClDeviceContext& operator=(const ClDeviceContext&) = delete;

    const ClDevice& device() const { return device_; }
    const cl::Context& context() const { return context_; }
    const cl::CommandQueue& queue() const { return queue_; }

    // Held around every use of the queue and of the program table.
    std::unique_lock<std::mutex> lock() const { return std::unique_lock<std::mutex>(mutex_); }

    // The program of the embedded kernel source built with `options`: built
    // (or loaded from the disk kernel cache in `cache_dir`, see ProgramCache)
    // on first use, then kept. The caller holds lock().
    ProgramHandle program(const std::string& options, const std::optional<std::filesystem::path>& cache_dir);

    // The pinned staging of queries on host arrays (cl_query_staging.h), made
    // at first use and kept. The caller holds lock().
    QueryStaging& query_staging() const;

    ~ClDeviceContext();

private:
    ClDevice device_;
    cl::Context context_;
    cl::CommandQueue queue_;
    mutable std::mutex mutex_;
    struct Built {
        cl::Program program;
        bool cache_hit = false;
    };
    std::map<std::string, Built> programs_;  // by kernel options
    mutable std::unique_ptr<QueryStaging> staging_;  // after the queue: goes first
};

}  // namespace kdrt::detail::ocl
