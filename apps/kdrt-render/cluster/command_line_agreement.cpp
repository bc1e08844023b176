#include "cluster/command_line_agreement.h"

#include "cluster/protocol.h"

#include <mpi.h>

#include <vector>

namespace kdrt::cluster {
namespace {

const char* action_name(int action, int exit_code) {
    switch (action) {
        case 0: return "a render";
        case 1: return "--list-devices";
        default: return exit_code == 0 ? "--help or --version" : "an invalid command line";
    }
}

// Every rank's request, gathered on rank 0 (empty elsewhere).
std::vector<std::pair<std::string, RankRequest>> gather(const MpiSession& session, const RankRequest& mine) {
    Packer p;
    p.put_string(session.name());
    p.put<std::int32_t>(mine.action);
    p.put<std::int32_t>(mine.exit_code);
    p.put_string(mine.message);
    const int size = static_cast<int>(p.bytes.size());
    std::vector<int> sizes(static_cast<std::size_t>(session.size())), offsets(sizes.size());
    check_mpi(MPI_Gather(&size, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
    int total = 0;
    for (std::size_t r = 0; r < sizes.size(); ++r) {
        offsets[r] = total;
        total += sizes[r];
    }
    std::vector<std::uint8_t> all(static_cast<std::size_t>(session.rank() == 0 ? total : 0));
    check_mpi(MPI_Gatherv(p.bytes.data(), size, MPI_BYTE, all.data(), sizes.data(), offsets.data(), MPI_BYTE, 0,
                          MPI_COMM_WORLD),
              "MPI_Gatherv");
    std::vector<std::pair<std::string, RankRequest>> requests;
    for (std::size_t r = 0; session.rank() == 0 && r < sizes.size(); ++r) {
        const std::vector<std::uint8_t> bytes(all.begin() + offsets[r], all.begin() + offsets[r] + sizes[r]);
        Unpacker u(bytes);
        std::pair<std::string, RankRequest> request;
        request.first = u.get_string();
        request.second.action = u.get<std::int32_t>();
        request.second.exit_code = u.get<std::int32_t>();
        request.second.message = u.get_string();
        requests.push_back(std::move(request));
    }
    return requests;
}

// Rank 0's decision over every rank's request.
Agreement decide(const std::vector<std::pair<std::string, RankRequest>>& requests) {
    const RankRequest& first = requests[0].second;
    for (std::size_t r = 0; r < requests.size(); ++r) {
        const auto& [name, request] = requests[r];
        if (request.action == 2 && request.exit_code != 0)
            return {false, 2, (r == 0 ? "" : name + ": ") + request.message, true};
    }
    for (std::size_t r = 1; r < requests.size(); ++r) {
        const auto& [name, request] = requests[r];
        if (request.action != first.action)
            return {false, 2,
                    name + ": its command line asks for " + action_name(request.action, request.exit_code) +
                        ", rank 0's for " + action_name(first.action, first.exit_code) +
                        "; give every rank the same command line",
                    true};
    }
    if (first.action == 2) return {false, 0, first.message, false};  // --help or --version everywhere
    return {true, 0, {}, false};
}

}  // namespace

Agreement agree_on_command_line(const MpiSession& session, const RankRequest& mine) {
    const auto requests = gather(session, mine);
    Agreement agreed;
    if (session.rank() == 0) agreed = decide(requests);
    std::int32_t decision[2] = {agreed.proceed ? 1 : 0, agreed.exit_code};
    check_mpi(MPI_Bcast(decision, 2, MPI_INT32_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
    agreed.proceed = decision[0] != 0;
    agreed.exit_code = decision[1];
    return agreed;
}

}  // namespace kdrt::cluster
