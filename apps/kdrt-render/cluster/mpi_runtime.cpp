#include "cluster/mpi_runtime.h"

#include "common/atomic_file.h"

#include <kdrt/error.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <cstdlib>
#include <string>
#include <thread>

#include <unistd.h>

namespace kdrt::cluster {

bool launched_by_mpirun() {
    return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr;
}

namespace {

char termination_text[512];
std::size_t termination_length = 0;

extern "C" void on_termination(int signal) {
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, termination_text, termination_length);
    detail::remove_live_temporaries();  // a frame being written: no temporary left beside it
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

}  // namespace

void explain_termination(const std::string& text) {
    termination_length = std::min(text.size(), sizeof termination_text);
    std::memcpy(termination_text, text.data(), termination_length);
    struct sigaction action {};
    action.sa_handler = on_termination;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
}

void stop_explaining_termination() {
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
}

void check_mpi(int rc, const char* call) {
    if (rc == MPI_SUCCESS) return;
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(rc, text, &length);
    throw Error(ErrorCode::Device, std::string(call) + " failed: " + std::string(text, static_cast<std::size_t>(length)));
}

MpiSession::MpiSession(int& argc, char**& argv) {
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
    // Errors come back as return codes (check_mpi), not as an abort inside MPI.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    char host[MPI_MAX_PROCESSOR_NAME];
    int length = 0;
    MPI_Get_processor_name(host, &length);
    host_.assign(host, static_cast<std::size_t>(length));
    if (const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_RANK")) local_rank_ = std::atoi(local);
    if (provided < MPI_THREAD_SERIALIZED)
        throw Error(ErrorCode::Unsupported, "this MPI library does not allow calls from several threads in turn "
                                            "(MPI_THREAD_SERIALIZED)");
}

MpiSession::~MpiSession() { MPI_Finalize(); }

std::string MpiSession::name() const { return "rank " + std::to_string(rank_) + " (" + host_ + ")"; }

void wait_without_spinning(MPI_Request& request, MPI_Status* status, int max_sleep_us) {
    int sleep_us = 2;
    for (;;) {
        int done = 0;
        check_mpi(MPI_Test(&request, &done, status), "MPI_Test");
        if (done) return;
        std::this_thread::sleep_for(std::chrono::microseconds(sleep_us));
        sleep_us = std::min(sleep_us * 2, max_sleep_us);
    }
}

}  // namespace kdrt::cluster
