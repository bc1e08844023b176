// kdrt-render under mpirun (a -DKDRT_MPI=ON build): every rank runs the job
// (cluster/cluster_job.h); rank 0 checks the outputs, loads the scene,
// writes the frames and prints the statistics.
#pragma once

#include "command_line.h"

#include "cluster/mpi_runtime.h"

#include <exception>
#include <functional>

namespace kdrt::cli {

// `exit_code_of`: the exit status main gives an error, passed to every rank.
int run_cluster(const cluster::MpiSession& session, const Args& a,
                const std::function<int(const std::exception_ptr&)>& exit_code_of);

}  // namespace kdrt::cli
