// The MPI side of the cluster build: start-up and shut-down, who we are, and
// waiting for a request without spinning. Open MPI's blocking calls
// busy-poll, which steals a core from the renderer when ranks share a
// machine (two ranks on two cores lose a third of their speed); every wait
// here tests its request and sleeps between tests instead.
#pragma once

#include <mpi.h>

#include <string>

namespace kdrt::cluster {

// Whether this process was started by mpirun / mpiexec (Open MPI sets
// OMPI_COMM_WORLD_SIZE; MPICH and Slurm's PMI set PMI_SIZE). Without it,
// kdrt-render never initialises MPI and behaves as the single-process build.
bool launched_by_mpirun();

// MPI_Init_thread (MPI_THREAD_SERIALIZED: a rank's device threads take turns
// at the tile source) in the constructor, MPI_Finalize in the destructor.
class MpiSession {
public:
    MpiSession(int& argc, char**& argv);
    ~MpiSession();
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    // The rank's number among the ranks of its host (OMPI_COMM_WORLD_LOCAL_RANK; 0 if unknown).
    int local_rank() const { return local_rank_; }
    const std::string& host() const { return host_; }
    // "rank N (host)", how messages name a rank.
    std::string name() const;

private:
    int rank_ = 0, size_ = 1, local_rank_ = 0;
    std::string host_;
};

// Waits for `request` to complete, testing it and sleeping in between
// (starting at a few microseconds, backing off to `max_sleep_us`).
void wait_without_spinning(MPI_Request& request, MPI_Status* status = MPI_STATUS_IGNORE, int max_sleep_us = 500);

// When mpirun ends the job (SIGTERM: another rank died or failed), rank 0
// says so before it goes, since mpirun's own message names the rank but not
// what became of the output. Async-signal-safe: the text is made here, and
// the handler unlinks the temporaries of files being written
// (detail::remove_live_temporaries), so the frame in progress leaves nothing.
// stop_explaining_termination() restores the default once rank 0 has
// reported the job's end itself.
void explain_termination(const std::string& text);
void stop_explaining_termination();

// Throws kdrt::Error(Device) with MPI's text for a failed call.
void check_mpi(int rc, const char* call);

}  // namespace kdrt::cluster
