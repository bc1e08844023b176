// kdrt/opencl_interop.h before an application's <CL/cl.h> of OpenCL 3.0: the
// header sets no target version and includes no OpenCL header, so the
// application's include still declares the 2.0+ API
// (clCreateCommandQueueWithProperties). Its twin is
// test_opencl_interop_header_before.cpp.
#include <kdrt/opencl_interop.h>

#define CL_TARGET_OPENCL_VERSION 300
#include <CL/cl.h>

#include <catch2/catch.hpp>

#include <type_traits>

TEST_CASE("opencl_interop.h before <CL/cl.h> 3.0: the 2.0 API is declared, the handles are Khronos'", "[opencl]") {
    // The handle types kdrt declared are the ones <CL/cl.h> declares.
    static_assert(std::is_same_v<decltype(&kdrt::wrap_opencl_device),
                                 kdrt::Device (*)(cl_context, cl_device_id, cl_command_queue)>);
    static_assert(std::is_same_v<cl_mem, struct _cl_mem*>);
    cl_command_queue (*create)(cl_context, cl_device_id, const cl_queue_properties*, cl_int*) =
        &clCreateCommandQueueWithProperties;
    CHECK(create != nullptr);
}
