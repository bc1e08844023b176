#include "cluster/mpi_messages.h"

#include "cluster/mpi_runtime.h"

#include <algorithm>

namespace kdrt::cluster {

namespace {
constexpr std::int64_t kBroadcastChunk = std::int64_t{1} << 30;  // MPI counts are ints
}  // namespace

void broadcast_header(SetupHeader& h) {
    MPI_Request request;
    check_mpi(MPI_Ibcast(&h, sizeof h, MPI_BYTE, 0, MPI_COMM_WORLD, &request), "MPI_Ibcast");
    wait_without_spinning(request);
}

void broadcast_payload(std::uint8_t* data, std::int64_t bytes) {
    for (std::int64_t at = 0; at < bytes; at += kBroadcastChunk) {
        MPI_Request request;
        check_mpi(MPI_Ibcast(data + at, static_cast<int>(std::min(kBroadcastChunk, bytes - at)), MPI_BYTE, 0,
                             MPI_COMM_WORLD, &request),
                  "MPI_Ibcast");
        wait_without_spinning(request, MPI_STATUS_IGNORE, 50);
    }
}

void send_bytes(const std::vector<std::uint8_t>& bytes, int to, int tag) {
    MPI_Request request;
    check_mpi(MPI_Isend(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD, &request),
              "MPI_Isend");
    wait_without_spinning(request);
}

std::vector<std::uint8_t> receive_bytes(const MPI_Status& probed) {
    int count = 0;
    check_mpi(MPI_Get_count(&probed, MPI_BYTE, &count), "MPI_Get_count");
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(count));
    check_mpi(MPI_Recv(bytes.data(), count, MPI_BYTE, probed.MPI_SOURCE, probed.MPI_TAG, MPI_COMM_WORLD,
                       MPI_STATUS_IGNORE),
              "MPI_Recv");
    return bytes;
}

}  // namespace kdrt::cluster
