#include "cl_buffer_queries.h"

#include "stats.h"

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/opencl_interop.h>

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <optional>
#include <vector>

namespace kdrt::bench {

namespace {

void check(cl_int status, const char* what) {
    if (status != CL_SUCCESS) throw Error(ErrorCode::Device, std::string(what) + " failed (OpenCL error " + std::to_string(status) + ")");
}

std::string device_string(cl_device_id d, cl_device_info what) {
    std::size_t n = 0;
    check(clGetDeviceInfo(d, what, 0, nullptr, &n), "clGetDeviceInfo");
    std::string s(n, '\0');
    check(clGetDeviceInfo(d, what, n, s.data(), nullptr), "clGetDeviceInfo");
    while (!s.empty() && s.back() == '\0') s.pop_back();
    return s;
}

// The cl_device_id of the device kdrt opens for `spec`, found by its name.
cl_device_id find_device(const std::string& spec) {
    const DeviceInfo info = Device::open(spec).info();
    if (info.id == "cpu") throw Error(ErrorCode::Device, "'" + spec + "' is no OpenCL device");
    cl_uint platforms = 0;
    check(clGetPlatformIDs(0, nullptr, &platforms), "clGetPlatformIDs");
    std::vector<cl_platform_id> p(platforms);
    check(clGetPlatformIDs(platforms, p.data(), nullptr), "clGetPlatformIDs");
    for (cl_platform_id platform : p) {
        cl_uint n = 0;
        if (clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 0, nullptr, &n) != CL_SUCCESS) continue;
        std::vector<cl_device_id> d(n);
        check(clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, n, d.data(), nullptr), "clGetDeviceIDs");
        for (cl_device_id id : d)
            if (device_string(id, CL_DEVICE_NAME) == info.name) return id;
    }
    throw Error(ErrorCode::Device, "no OpenCL device named '" + info.name + "'");
}

// A cl_mem released with its owner.
struct Buffer {
    cl_mem mem = nullptr;
    std::size_t bytes = 0;
    ~Buffer() { if (mem) clReleaseMemObject(mem); }
    void ensure(cl_context context, std::size_t size) {
        if (size <= bytes) return;
        if (mem) clReleaseMemObject(mem);
        cl_int status = CL_SUCCESS;
        mem = clCreateBuffer(context, CL_MEM_READ_WRITE, size, nullptr, &status);
        check(status, "clCreateBuffer");
        bytes = size;
    }
};

}  // namespace

struct ClBufferQueries::State {
    cl_context context = nullptr;
    cl_command_queue queue = nullptr;
    std::optional<Device> device;
    Buffer rays, hits, any;
    std::size_t count = 0;
    ~State() {
        device.reset();
        if (queue) clReleaseCommandQueue(queue);
        if (context) clReleaseContext(context);
    }
};

ClBufferQueries::ClBufferQueries(const std::string& device_spec) : s_(std::make_unique<State>()) {
    cl_device_id id = find_device(device_spec);
    cl_int status = CL_SUCCESS;
    s_->context = clCreateContext(nullptr, 1, &id, nullptr, nullptr, &status);
    check(status, "clCreateContext");
    s_->queue = clCreateCommandQueue(s_->context, id, 0, &status);
    check(status, "clCreateCommandQueue");
    s_->device = wrap_opencl_device(s_->context, id, s_->queue);
}

ClBufferQueries::~ClBufferQueries() = default;

const Device& ClBufferQueries::device() const { return *s_->device; }

void ClBufferQueries::upload(std::span<const QueryRay> rays) {
    s_->count = rays.size();
    s_->rays.ensure(s_->context, rays.size_bytes());
    s_->hits.ensure(s_->context, rays.size() * sizeof(QueryHit));
    s_->any.ensure(s_->context, rays.size());
    check(clEnqueueWriteBuffer(s_->queue, s_->rays.mem, CL_TRUE, 0, rays.size_bytes(), rays.data(), 0, nullptr, nullptr),
          "clEnqueueWriteBuffer");
}

double ClBufferQueries::time_intersect(const CommittedScene& scene, std::int32_t* ids, float* ts) {
    const Stopwatch clock;
    intersect(scene, s_->rays.mem, s_->hits.mem, s_->count);
    const double ms = clock.ms();
    std::vector<QueryHit> hits(s_->count);
    check(clEnqueueReadBuffer(s_->queue, s_->hits.mem, CL_TRUE, 0, hits.size() * sizeof(QueryHit), hits.data(), 0,
                              nullptr, nullptr),
          "clEnqueueReadBuffer");
    for (std::size_t i = 0; i < hits.size(); ++i) {
        ids[i] = hits[i].object == KDRT_NO_HIT ? -1 : static_cast<std::int32_t>(hits[i].object);
        ts[i] = hits[i].t;
    }
    return ms;
}

double ClBufferQueries::time_occluded(const CommittedScene& scene, std::int32_t* ids) {
    const Stopwatch clock;
    occluded(scene, s_->rays.mem, s_->any.mem, s_->count);
    const double ms = clock.ms();
    std::vector<std::uint8_t> any(s_->count);
    check(clEnqueueReadBuffer(s_->queue, s_->any.mem, CL_TRUE, 0, any.size(), any.data(), 0, nullptr, nullptr),
          "clEnqueueReadBuffer");
    for (std::size_t i = 0; i < any.size(); ++i) ids[i] = any[i];
    return ms;
}

}  // namespace kdrt::bench
