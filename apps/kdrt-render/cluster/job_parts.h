// The two sides of a cluster job (cluster_job.h) and what they share.
#pragma once

#include "cluster/cluster_job.h"

#include <chrono>
#include <string>
#include <vector>

namespace kdrt::cluster::detail {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The frame-level options every rank renders tiles with (the tree comes in memory).
inline RenderOptions tile_options(const JobSpec& spec) {
    RenderOptions o = spec.options;
    o.load_tree.reset();
    o.save_tree.reset();
    o.tree_cache_dir.reset();
    o.progress = nullptr;
    return o;
}

// Rank 0's exit status for `error` (JobSpec::exit_code_of), in 1 .. 255.
inline int exit_code_for(const JobSpec& spec, const std::exception_ptr& error) {
    const int code = spec.exit_code_of && error ? spec.exit_code_of(error) : 1;
    return code >= 1 && code <= 255 ? code : 1;
}

inline void name_shares(std::vector<DeviceShare>& shares, const std::string& rank_name) {
    for (DeviceShare& s : shares) s.device_name = rank_name + ": " + s.device_name;
}

void run_worker(const MpiSession& session, const JobSpec& spec);
void run_rank0(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
               const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats);

}  // namespace kdrt::cluster::detail
