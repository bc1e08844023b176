// kdrt/opencl_interop.h after an application's <CL/cl.h> of OpenCL 3.0: the
// header adds only its own declarations, so the application keeps the 2.0+
// API it asked for (clCreateCommandQueueWithProperties) and hands kdrt a
// queue made with it. Its twin, test_opencl_interop_header_after.cpp,
// includes the two the other way round.
#define CL_TARGET_OPENCL_VERSION 300
#include <CL/cl.h>

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/opencl_interop.h>

#include <catch2/catch.hpp>

#include <type_traits>
#include <vector>

namespace {

// The first device of the first platform that has one, or none.
cl_device_id first_device() {
    cl_uint count = 0;
    if (clGetPlatformIDs(0, nullptr, &count) != CL_SUCCESS || count == 0) return nullptr;
    std::vector<cl_platform_id> platforms(count);
    clGetPlatformIDs(count, platforms.data(), nullptr);
    for (cl_platform_id p : platforms) {
        cl_device_id d = nullptr;
        if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 1, &d, nullptr) == CL_SUCCESS && d) return d;
    }
    return nullptr;
}

}  // namespace

TEST_CASE("opencl_interop.h after <CL/cl.h> 3.0: a queue made with the 2.0 API is wrapped", "[opencl]") {
    static_assert(std::is_same_v<decltype(&kdrt::wrap_opencl_device),
                                 kdrt::Device (*)(cl_context, cl_device_id, cl_command_queue)>);
    cl_device_id device = first_device();
    if (!device) {
        WARN("no OpenCL device: skipping");
        return;
    }
    cl_int status = CL_SUCCESS;
    cl_context context = clCreateContext(nullptr, 1, &device, nullptr, nullptr, &status);
    REQUIRE(status == CL_SUCCESS);
    cl_command_queue queue = clCreateCommandQueueWithProperties(context, device, nullptr, &status);
    REQUIRE(status == CL_SUCCESS);
    {
        const kdrt::Device wrapped = kdrt::wrap_opencl_device(context, device, queue);
        CHECK(wrapped.is_opencl());
    }
    clReleaseCommandQueue(queue);
    clReleaseContext(context);
}
