// kdrt's ray queries on rays already in device memory: the application's own
// OpenCL context around the same device (kdrt/opencl_interop.h); each call
// uploads the rays and reads the answers back outside the time it reports.
// What a caller that keeps its rays on a GPU gets, beside intersect()/occluded()
// on host arrays, whose time includes the upload and read-back.
#pragma once

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/layout.h>
#include <kdrt/scene.h>

#include <cstdint>
#include <memory>
#include <span>

namespace kdrt::bench {

class OpenClBuffers {
public:
    // A context and queue of its own on the OpenCL device `info` names (by
    // platform, name and place among devices of that name), and the scene
    // committed there. Throws when no such device.
    OpenClBuffers(const DeviceInfo& info, const Scene& scene, const CommitOptions& commit);
    ~OpenClBuffers();
    OpenClBuffers(const OpenClBuffers&) = delete;
    OpenClBuffers& operator=(const OpenClBuffers&) = delete;

    // Uploads the rays (not timed), runs the query on the device's buffers
    // (timed: its milliseconds are returned), then reads the answers back.
    double closest(std::span<const QueryRay> rays, std::span<QueryHit> hits);
    double any(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded);

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace kdrt::bench
