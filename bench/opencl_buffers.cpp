#include "opencl_buffers.h"

#include "common.h"

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <kdrt/error.h>
#include <kdrt/opencl_interop.h>

#include <optional>
#include <string>
#include <vector>

namespace kdrt::bench {

namespace {

// A string property of a platform or device (clGetPlatformInfo, clGetDeviceInfo).
template <class Handle, class Property, class Get>
std::string info_string(Handle handle, Property what, Get get) {
    std::size_t n = 0;
    get(handle, what, 0, nullptr, &n);
    std::string s(n, '\0');
    get(handle, what, n, s.data(), nullptr);
    s.resize(std::string(s.c_str()).size());
    // Trimmed as kdrt lists them: some drivers pad names with spaces.
    const auto first = s.find_first_not_of(' '), last = s.find_last_not_of(' ');
    return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
}

// The device kdrt lists as `info`: the same platform and name, and among
// devices of that platform and name (identical GPUs), the same place in the list.
cl_device_id find_device(const DeviceInfo& info) {
    std::size_t ordinal = 0;
    bool listed = false;
    for (const DeviceInfo& d : list_devices()) {
        if ((listed = d.id == info.id)) break;
        ordinal += d.platform == info.platform && d.name == info.name;
    }
    if (!listed) throw Error(ErrorCode::Device, info.id + ": not among kdrt's listed devices");
    cl_uint platforms = 0;
    clGetPlatformIDs(0, nullptr, &platforms);
    std::vector<cl_platform_id> ps(platforms);
    if (platforms) clGetPlatformIDs(platforms, ps.data(), nullptr);
    for (cl_platform_id p : ps) {
        if (info_string(p, CL_PLATFORM_NAME, clGetPlatformInfo) != info.platform) continue;
        cl_uint devices = 0;
        if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &devices) != CL_SUCCESS) continue;
        std::vector<cl_device_id> ds(devices);
        clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, devices, ds.data(), nullptr);
        for (cl_device_id d : ds)
            if (info_string(d, CL_DEVICE_NAME, clGetDeviceInfo) == info.name && ordinal-- == 0) return d;
    }
    throw Error(ErrorCode::Device, info.id + ": no OpenCL device named '" + info.name + "' on '" + info.platform + "'");
}

void check(cl_int status, const char* what) {
    if (status != CL_SUCCESS) throw Error(ErrorCode::Device, std::string(what) + " failed: " + std::to_string(status));
}

}  // namespace

// The application's side: its context and queue, kdrt's device and scene on
// them, and the ray and result buffers, grown as ray sets need.
struct OpenClBuffers::State {
    cl_context context = nullptr;
    cl_command_queue queue = nullptr;
    std::optional<Device> device;
    std::optional<CommittedScene> scene;
    cl_mem rays = nullptr, out = nullptr;
    std::size_t ray_bytes = 0, out_bytes = 0;

    ~State() {
        scene.reset();  // kdrt's objects before the context they live in
        device.reset();
        if (rays) clReleaseMemObject(rays);
        if (out) clReleaseMemObject(out);
        if (queue) clReleaseCommandQueue(queue);
        if (context) clReleaseContext(context);
    }

    // `buffer` of at least `bytes` (grown, never shrunk; `size` its size, 0 while it has none).
    void reserve(cl_mem& buffer, std::size_t& size, std::size_t bytes, cl_mem_flags flags) {
        if (bytes <= size) return;
        if (buffer) clReleaseMemObject(buffer);
        buffer = nullptr;
        size = 0;
        cl_int status = CL_SUCCESS;
        buffer = clCreateBuffer(context, flags, bytes, nullptr, &status);
        check(status, "clCreateBuffer");
        size = bytes;
    }

    template <class Query, class T>
    double run(std::span<const QueryRay> rays_in, std::span<T> results, Query query) {
        reserve(rays, ray_bytes, rays_in.size_bytes(), CL_MEM_READ_ONLY);
        reserve(out, out_bytes, results.size_bytes(), CL_MEM_READ_WRITE);
        check(clEnqueueWriteBuffer(queue, rays, CL_TRUE, 0, rays_in.size_bytes(), rays_in.data(), 0, nullptr, nullptr),
              "clEnqueueWriteBuffer");
        const Stopwatch clock;
        query(*scene, rays, out, rays_in.size());
        const double ms = clock.ms();
        check(clEnqueueReadBuffer(queue, out, CL_TRUE, 0, results.size_bytes(), results.data(), 0, nullptr, nullptr),
              "clEnqueueReadBuffer");
        return ms;
    }
};

OpenClBuffers::OpenClBuffers(const DeviceInfo& info, const Scene& scene, const CommitOptions& commit)
    : state_(std::make_unique<State>()) {
    cl_device_id d = find_device(info);
    cl_int status = CL_SUCCESS;
    state_->context = clCreateContext(nullptr, 1, &d, nullptr, nullptr, &status);
    check(status, "clCreateContext");
    state_->queue = clCreateCommandQueue(state_->context, d, 0, &status);
    check(status, "clCreateCommandQueue");
    state_->device.emplace(wrap_opencl_device(state_->context, d, state_->queue));
    state_->scene.emplace(CommittedScene::commit(*state_->device, scene, commit));
}

OpenClBuffers::~OpenClBuffers() = default;

double OpenClBuffers::closest(std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    return state_->run(rays, hits, [](const CommittedScene& s, cl_mem r, cl_mem h, std::size_t n) { intersect(s, r, h, n); });
}

double OpenClBuffers::any(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) {
    return state_->run(rays, occluded,
                    [](const CommittedScene& s, cl_mem r, cl_mem o, std::size_t n) { kdrt::occluded(s, r, o, n); });
}

}  // namespace kdrt::bench
