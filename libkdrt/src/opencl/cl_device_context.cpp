#include "opencl/cl_device_context.h"

#include "opencl/cl_error.h"
#include "opencl/cl_query_staging.h"
#include "opencl/embedded_cl.h"
#include "opencl/program_cache.h"

#include <kdrt/error.h>

#include <algorithm>
#include <cstdio>

namespace kdrt::detail::ocl {

namespace {

[[noreturn]] void refuse(const std::string& why) {
    throw Error(ErrorCode::Device, "wrap_opencl_device: " + why);
}

// "OpenCL 1.2 pocl ..." / "OpenCL C 1.2 ..." -> 102; 0 when unreadable.
int version_number(const std::string& text, const std::string& prefix) {
    if (text.compare(0, prefix.size(), prefix) != 0) return 0;
    int major = 0, minor = 0;
    if (std::sscanf(text.c_str() + prefix.size(), "%d.%d", &major, &minor) != 2) return 0;
    return major * 100 + minor;
}

}  // namespace

ClDeviceContext::ClDeviceContext(const ClDevice& device) : device_(device) {
    guard_cl("creating an OpenCL context on " + device.info.id, [&] {
        context_ = cl::Context(device_.device);
        queue_ = cl::CommandQueue(context_, device_.device);
    });
}

ClDeviceContext::ClDeviceContext(cl_context context, cl_device_id device, cl_command_queue queue) {
    if (!context || !device || !queue)
        refuse(std::string("a null ") + (!context ? "cl_context" : !device ? "cl_device_id" : "cl_command_queue"));
    // Each handle is checked by asking it something: a stale or foreign handle fails here, named.
    auto queue_info = [&](cl_command_queue_info what, auto& out) {
        const cl_int err = clGetCommandQueueInfo(queue, what, sizeof out, &out, nullptr);
        if (err != CL_SUCCESS) refuse(std::string("the command queue cannot be queried: ") + cl_error_name(err));
    };
    cl_context queue_context = nullptr;
    cl_device_id queue_device = nullptr;
    cl_command_queue_properties properties = 0;
    queue_info(CL_QUEUE_CONTEXT, queue_context);
    queue_info(CL_QUEUE_DEVICE, queue_device);
    queue_info(CL_QUEUE_PROPERTIES, properties);
    if (queue_context != context) refuse("the command queue belongs to another cl_context than the one given");
    if (queue_device != device) refuse("the command queue belongs to another cl_device_id than the one given");
    if ((properties & CL_QUEUE_OUT_OF_ORDER_EXEC_MODE_ENABLE) != 0)
        refuse("the command queue is out of order; kdrt needs an in-order queue (its commands depend on each other)");
    cl_uint device_count = 0;
    if (cl_int err = clGetContextInfo(context, CL_CONTEXT_NUM_DEVICES, sizeof device_count, &device_count, nullptr);
        err != CL_SUCCESS)
        refuse(std::string("the cl_context cannot be queried: ") + cl_error_name(err));
    std::vector<cl_device_id> devices(device_count);
    if (device_count > 0)
        clGetContextInfo(context, CL_CONTEXT_DEVICES, device_count * sizeof(cl_device_id), devices.data(), nullptr);
    if (std::find(devices.begin(), devices.end(), device) == devices.end())
        refuse("the cl_device_id is not one of the cl_context's devices");

    guard_cl("wrap_opencl_device", [&] {
        context_ = cl::Context(context, true);
        queue_ = cl::CommandQueue(queue, true);
        device_ = describe_application_device(cl::Device(device, true));
    });
    const std::string name = device_.info.name + " (" + device_.info.platform + ")";
    if (!device_.device.getInfo<CL_DEVICE_COMPILER_AVAILABLE>())
        refuse("the device " + name + " has no OpenCL C compiler; kdrt builds its kernels from source");
    if (!device_.device.getInfo<CL_DEVICE_AVAILABLE>()) refuse("the device " + name + " is not available");
    const std::string version = device_.device.getInfo<CL_DEVICE_OPENCL_C_VERSION>();
    if (version_number(version, "OpenCL C ") < 102)
        refuse("the device " + name + " supports '" + version + "'; kdrt's kernels need OpenCL C 1.2");
}

ClDeviceContext::~ClDeviceContext() = default;

QueryStaging& ClDeviceContext::query_staging() const {
    if (!staging_) staging_ = std::make_unique<QueryStaging>(*this);
    return *staging_;
}

ProgramHandle ClDeviceContext::program(const std::string& options,
                                       const std::optional<std::filesystem::path>& cache_dir) {
    ProgramHandle handle;
    if (auto it = programs_.find(options); it != programs_.end()) {
        handle.program = it->second.program;
        handle.cache_hit = it->second.cache_hit;
        return handle;
    }
    const ProgramCache cache(cache_dir);
    BuiltProgram built = cache.build(context_, device_, assemble_kernel_source(), options);
    if (!cache.problem().empty()) handle.warnings.push_back(cache.problem());
    if (!built.cache_warning.empty()) handle.warnings.push_back(built.cache_warning);
    handle.program = built.program;
    handle.compiled_now = true;
    handle.cache_hit = built.cache_hit;
    handle.compile_ms = built.compile_ms;
    programs_.emplace(options, Built{std::move(built.program), built.cache_hit});
    return handle;
}

}  // namespace kdrt::detail::ocl
