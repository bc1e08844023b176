#include "cluster_run.h"

#include "camera_orbit.h"
#include "frame_output.h"
#include "input.h"
#include "interrupt.h"
#include "output_check.h"
#include "stats_json.h"

#include "cluster/cluster_job.h"

#include <kdrt/image.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <utility>
#include <vector>

namespace kdrt::cli {
namespace {

nlohmann::ordered_json cluster_json(const cluster::JobStats& s) {
    nlohmann::ordered_json shares = nlohmann::ordered_json::array();
    for (const DeviceShare& d : s.shares)
        shares.push_back({{"device", d.device_name}, {"tiles", d.tiles}, {"pixels", d.pixels}, {"busy_ms", d.busy_ms},
                          {"rays", d.rays.total()}});
    return {{"ranks", s.ranks},           {"prepare_ms", s.prepare_ms},   {"commit_ms", s.commit_ms},
            {"serialize_ms", s.serialize_ms}, {"broadcast_ms", s.broadcast_ms}, {"broadcast_bytes", s.broadcast_bytes},
            {"render_ms", s.render_ms},   {"receive_ms", s.receive_ms},   {"assemble_ms", s.assemble_ms},
            {"output_ms", s.output_ms},   {"tiles", s.tiles},             {"decoded_ms", s.decoded_ms},
            {"ready_ms", s.ready_ms},
            {"shares", shares}};
}

cluster::JobSpec job_spec(const Args& a, const std::function<int(const std::exception_ptr&)>& exit_code_of) {
    cluster::JobSpec spec;
    spec.options = a.render;
    spec.options.commit.progress = nullptr;
    spec.options.frame.progress = nullptr;
    spec.frames = a.frames;
    spec.camera = [frames = a.frames](const Camera& c, int frame) { return orbit_camera(c, frame, frames); };
    spec.exit_code_of = exit_code_of;
    if (a.tile) {
        spec.tile_width = a.tile_size.width;
        spec.tile_height = a.tile_size.height;
    }
    return spec;
}

}  // namespace

int run_cluster(const cluster::MpiSession& session, const Args& a,
                const std::function<int(const std::exception_ptr&)>& exit_code_of) {
    const cluster::JobSpec spec = job_spec(a, exit_code_of);
    auto prepare = [&a] {
        check_outputs(a);  // every frame's outputs
        if (!a.output.empty()) check_image_output(a.output);
        return load_input(a);
    };
    std::vector<std::pair<int, nlohmann::ordered_json>> frame_stats;
    auto frame_done = [&](int frame, const Scene& scene, RenderResult&& r) {
        stop_if_interrupted();
        const double write_ms = finish_frame(a, scene, r, frame);
        if (a.stats_json) frame_stats.emplace_back(frame, stats_json(a, scene, a.render, r, {}, write_ms));
    };
    cluster::JobStats stats;
    cluster::run_job(session, spec, prepare, frame_done, stats);
    std::sort(frame_stats.begin(), frame_stats.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (auto& [frame, j] : frame_stats) {
        j["cluster"] = cluster_json(stats);
        print_stats(a, std::move(j), frame);
    }
    return 0;
}

}  // namespace kdrt::cli
