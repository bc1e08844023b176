// Under mpirun every rank parses its own command line (mpirun's "a : b" form
// gives each its own), and a rank whose command line fails (a bad value, or
// --help or --version on some ranks only) must not leave the others waiting
// for it. So, before anything else, every rank tells the others what its
// command line asks for, and all go on only when all ask for the same:
// a render (or a device list). Otherwise every rank exits with the same
// status (2 for a usage error, 0 when all asked for --help or --version)
// and rank 0 alone prints the message, naming the rank it came from.
#pragma once

#include "cluster/mpi_runtime.h"

#include <string>

namespace kdrt::cluster {

struct RankRequest {
    int action = 0;     // 0 render, 1 list devices, 2 exit (help, version or a usage error)
    int exit_code = 0;  // action 2: 0 (help, version) or 2 (usage error)
    std::string message;  // action 2: the help or version text, or the error
};

struct Agreement {
    bool proceed = false;      // every rank asked for the same render or list
    int exit_code = 0;         // otherwise every rank's exit status
    std::string message;       // rank 0: what to print (empty on the other ranks)
    bool message_is_error = false;  // print on stderr as an error, else on stdout
};

// Collective: every rank calls it once, right after parsing.
Agreement agree_on_command_line(const MpiSession& session, const RankRequest& mine);

}  // namespace kdrt::cluster
