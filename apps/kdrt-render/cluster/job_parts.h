// The two sides of a cluster job (cluster_job.h) and what they share.
#pragma once

#include "cluster/cluster_job.h"

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace kdrt::cluster::detail {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The options every rank commits and renders tiles with (the tree comes in memory).
inline RenderOptions tile_options(const JobSpec& spec) {
    RenderOptions o = spec.options;
    o.commit.tree_files = {};
    o.commit.progress = nullptr;
    o.frame.progress = nullptr;
    return o;
}

// Rank 0's exit status for `error` (JobSpec::exit_code_of), in 1 .. 255.
inline int exit_code_for(const JobSpec& spec, const std::exception_ptr& error) {
    const int code = spec.exit_code_of && error ? spec.exit_code_of(error) : 1;
    return code >= 1 && code <= 255 ? code : 1;
}

// The options that decide a frame's pixels, by their kdrt-render names. Every
// rank parses its own command line (mpirun's "a : b" form can give each its
// own): a rank rendering tiles with other values would make a frame of mixed
// pictures, so rank 0 compares them (device and speed options may differ).
inline std::vector<std::pair<std::string, std::string>> picture_options(const JobSpec& spec) {
    const FrameOptions& f = spec.options.frame;
    const CommitOptions& c = spec.options.commit;
    char epsilon[32];
    std::snprintf(epsilon, sizeof epsilon, "%.17g", c.accuracy.fixed_epsilon);
    const auto size = [](int v) { return v ? std::to_string(v) : std::string("the scene's"); };
    return {{"--frames", std::to_string(spec.frames)},
            {"--width", size(f.width)},
            {"--height", size(f.height)},
            {"--max-depth", size(f.max_depth)},
            {"--samples", size(f.samples)},
            {"--accel", to_string(c.accel)},
            {"--traversal", to_string(c.traversal)},
            {"--precision", to_string(c.accuracy.precision)},
            {"--triangle-test", to_string(c.accuracy.triangle_test)},
            {"--sphere-test", to_string(c.accuracy.sphere_test)},
            {"--self-intersection", to_string(c.accuracy.self_intersection)},
            {"--epsilon", epsilon},
            {"--features", c.all_features ? "all" : "scene"},
            {"--aov-ids", f.want_ids ? "given" : "not given"}};
}

inline void name_shares(std::vector<DeviceShare>& shares, const std::string& rank_name) {
    for (DeviceShare& s : shares) s.device_name = rank_name + ": " + s.device_name;
}

void run_worker(const MpiSession& session, const JobSpec& spec);
void run_rank0(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
               const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats);

}  // namespace kdrt::cluster::detail
