// Moving bytes between ranks: the setup broadcast and point-to-point byte
// messages, each waiting the way its phase needs (mpi_runtime.h).
#pragma once

#include "cluster/protocol.h"

#include <mpi.h>

#include <cstdint>
#include <vector>

namespace kdrt::cluster {

// The setup header from rank 0, waited for without spinning: the other
// ranks may wait here for the whole tree build.
void broadcast_header(SetupHeader& h);

// The scene and tree bytes, once every rank is ready for them (after the
// header). Data moves only while a rank is inside MPI, so the sleeps between
// tests stay short (50 us): about as fast as MPI_Bcast, which spins.
void broadcast_payload(std::uint8_t* data, std::int64_t bytes);

// A byte message, sent and waited for without spinning.
void send_bytes(const std::vector<std::uint8_t>& bytes, int to, int tag);

// Receives the message `probed` describes (MPI_Iprobe).
std::vector<std::uint8_t> receive_bytes(const MPI_Status& probed);

}  // namespace kdrt::cluster
