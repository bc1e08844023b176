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

std::string info_string(cl_platform_id p, cl_platform_info what) {
    std::size_t n = 0;
    clGetPlatformInfo(p, what, 0, nullptr, &n);
    std::string s(n, '\0');
    clGetPlatformInfo(p, what, n, s.data(), nullptr);
    return s.c_str();
}

std::string info_string(cl_device_id d, cl_device_info what) {
    std::size_t n = 0;
    clGetDeviceInfo(d, what, 0, nullptr, &n);
    std::string s(n, '\0');
    clGetDeviceInfo(d, what, n, s.data(), nullptr);
    return s.c_str();
}

// The device kdrt lists as `info`: the same platform and name, and among
// devices of that platform and name (identical GPUs), the same place in the list.
cl_device_id find_device(const DeviceInfo& info) {
    std::size_t ordinal = 0;
    for (const DeviceInfo& d : list_devices()) {
        if (d.id == info.id) break;
        ordinal += d.platform == info.platform && d.name == info.name;
    }
    cl_uint platforms = 0;
    clGetPlatformIDs(0, nullptr, &platforms);
    std::vector<cl_platform_id> ps(platforms);
    if (platforms) clGetPlatformIDs(platforms, ps.data(), nullptr);
    for (cl_platform_id p : ps) {
        if (info_string(p, CL_PLATFORM_NAME) != info.platform) continue;
        cl_uint devices = 0;
        if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &devices) != CL_SUCCESS) continue;
        std::vector<cl_device_id> ds(devices);
        clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, devices, ds.data(), nullptr);
        for (cl_device_id d : ds)
            if (info_string(d, CL_DEVICE_NAME) == info.name && ordinal-- == 0) return d;
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

    // Buffers of at least these sizes (grown, never shrunk).
    void reserve(std::size_t rb, std::size_t ob) {
        cl_int status = CL_SUCCESS;
        if (rb > ray_bytes) {
            if (rays) clReleaseMemObject(rays);
            ray_bytes = 0;
            rays = clCreateBuffer(context, CL_MEM_READ_ONLY, rb, nullptr, &status);
            check(status, "clCreateBuffer (rays)");
            ray_bytes = rb;
        }
        if (ob > out_bytes) {
            if (out) clReleaseMemObject(out);
            out_bytes = 0;
            out = clCreateBuffer(context, CL_MEM_READ_WRITE, ob, nullptr, &status);
            check(status, "clCreateBuffer (results)");
            out_bytes = ob;
        }
    }

    template <class Query, class T>
    double run(std::span<const QueryRay> rays_in, std::span<T> results, Query query) {
        reserve(rays_in.size_bytes(), results.size_bytes());
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
