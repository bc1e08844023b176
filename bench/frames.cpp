#include "frames.h"

#include "mesh_generator.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>

namespace kdrt::bench {

namespace {

// The camera orbited about its look-at point, around its up axis (Rodrigues' rotation).
Camera orbit(const Camera& c, double degrees) {
    const glm::dvec3 axis = glm::normalize(c.up);
    const glm::dvec3 v = c.position - c.look_at;
    const double a = degrees * 3.14159265358979323846 / 180.0;
    Camera moved = c;
    moved.position = c.look_at + v * std::cos(a) + glm::cross(axis, v) * std::sin(a) +
                     axis * glm::dot(axis, v) * (1.0 - std::cos(a));
    return moved;
}

struct FrameTimes {
    std::vector<double> wall_ms, update_ms, render_ms;
    std::uint64_t builds = 0, compiles = 0, upload_bytes = 0;  // the same in every sequence
};

Json measure(const NamedScene& in, const std::string& device, const FramesOptions& o) {
    std::vector<FrameTimes> frames(static_cast<std::size_t>(o.frames));
    FrameOptions frame;
    if (o.size > 0) frame.width = frame.height = o.size;
    for (int run = 0; run < o.runs; ++run) {
        Scene scene = in.scene;
        Stopwatch clock;  // frame 1 from nothing: a fresh device (context, queue, program cache), commit, render
        CommittedScene committed = CommittedScene::commit(Device::open(device), scene);
        for (FrameTimes& f : frames) {
            double update_ms = 0.0;
            if (&f != &frames.front()) {
                clock.restart();
                scene.camera = orbit(scene.camera, o.step_degrees);
                committed.update(scene);
                update_ms = clock.ms();
            }
            const RenderResult r = committed.render(frame);
            f.wall_ms.push_back(clock.ms());
            f.update_ms.push_back(update_ms);
            f.render_ms.push_back(r.stats.render_ms);
            f.builds = r.stats.builds;
            f.compiles = r.stats.compiles;
            f.upload_bytes = r.stats.geometry_upload_bytes;
        }
    }
    Json out = Json::array();
    for (const FrameTimes& f : frames) {
        out.push_back({{"wall_ms", median(f.wall_ms)}, {"update_ms", median(f.update_ms)},
                       {"render_ms", median(f.render_ms)}, {"builds", f.builds}, {"compiles", f.compiles},
                       {"geometry_upload_bytes", f.upload_bytes}});
        std::fprintf(stderr, "  %s on %s, frame %zu: %.1f ms\n", in.name.c_str(), device.c_str(), out.size(),
                     median(f.wall_ms));
    }
    return {{"input", in.name}, {"objects", in.scene.object_count()}, {"device", device}, {"frames", out}};
}

}  // namespace

Json run_frames(const FramesOptions& o) {
    if (o.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    if (o.frames < 2) throw Error(ErrorCode::InvalidArgument, "--frames must be at least 2");
    std::vector<std::string> devices = o.devices;
    if (devices.empty()) {
        devices = all_device_ids();
        if (devices.size() > 2) devices.resize(2);
    }
    std::vector<NamedScene> inputs = load_scenes(o.scenes, o.scenes_dir);
    for (const std::string& m : o.meshes) {
        Scene s = make_generated_scene(m);
        inputs.push_back({s.name, std::move(s)});
    }
    Json sequences = Json::array();
    for (const NamedScene& in : inputs)
        for (const std::string& d : devices) sequences.push_back(measure(in, d, o));
    return {{"settings", {{"frames", o.frames}, {"runs", o.runs}, {"size", o.size}, {"step_degrees", o.step_degrees}}},
            {"sequences", sequences}};
}

}  // namespace kdrt::bench
