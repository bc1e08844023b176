// A rank other than 0: its tiles come from rank 0 by message.
#pragma once

#include "cluster/protocol.h"
#include "cluster/tile_loop.h"

#include <mpi.h>

#include <deque>

namespace kdrt::cluster {

// Tiles asked of rank 0 ahead of need: kAhead requests stay in flight while a
// tile renders, so a rank does not wait a round trip (rank 0's serving thread
// may be asleep for up to half a millisecond) between tiles; results are sent
// without waiting for rank 0 to take them. Replies come in the order asked
// (MPI keeps the order of messages between two ranks).
class RemoteTiles : public TileSource {
public:
    static constexpr std::size_t kAhead = 2;

    std::optional<TileWork> next() override;
    void done(const TileWork& work, RenderResult&& r) override;
    // Before the Final message: every result delivered, every request answered.
    // A tile answered but not rendered (after a failure) is lost: rank 0 has stopped then.
    void finish();
    bool stopped() const { return stop_code_ != 0; }
    int stop_code() const { return stop_code_; }  // rank 0's exit status once stopped()

private:
    struct Ask {
        TileMessage reply{};
        MPI_Request request = MPI_REQUEST_NULL;
    };
    struct Send {
        std::vector<std::uint8_t> bytes;
        MPI_Request request;
    };
    void ask();
    void complete_sends(bool all);

    std::deque<Ask> asks_;
    bool no_more_ = false;
    int stop_code_ = 0;
    std::deque<Send> sends_;
};

}  // namespace kdrt::cluster
