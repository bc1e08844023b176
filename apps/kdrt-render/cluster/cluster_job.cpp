#include "cluster/cluster_job.h"

#include "cluster/job_parts.h"

namespace kdrt::cluster {

void run_job(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
             const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats) {
    if (session.rank() == 0) {
        try {
            detail::run_rank0(session, spec, prepare, frame_done, stats);
        } catch (...) {
            stop_explaining_termination();  // rank 0 reports this end itself
            throw;
        }
        stop_explaining_termination();
    } else
        detail::run_worker(session, spec);
}

}  // namespace kdrt::cluster
