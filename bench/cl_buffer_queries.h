// kdrt's OpenCL ray queries on the application's own cl_mem buffers
// (kdrt/opencl_interop.h): the bench makes its own context and in-order
// queue on the OpenCL device a spec names, wraps them as a kdrt::Device,
// uploads the rays once and times the queries with the results left on the
// device, as a GPU pipeline would use them. The results are read back after
// the clock stops, for validation.
#pragma once

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/layout.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace kdrt::bench {

class ClBufferQueries {
public:
    explicit ClBufferQueries(const std::string& device_spec);  // throws kdrt::Error(Device) if it is no OpenCL device
    ~ClBufferQueries();
    ClBufferQueries(const ClBufferQueries&) = delete;
    ClBufferQueries& operator=(const ClBufferQueries&) = delete;

    const Device& device() const;
    void upload(std::span<const QueryRay> rays);  // the rays of the following passes
    double time_intersect(const CommittedScene& scene, std::int32_t* ids, float* ts);
    double time_occluded(const CommittedScene& scene, std::int32_t* ids);

private:
    struct State;
    std::unique_ptr<State> s_;
};

}  // namespace kdrt::bench
