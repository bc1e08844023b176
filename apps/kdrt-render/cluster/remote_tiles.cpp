#include "cluster/remote_tiles.h"

#include "cluster/mpi_runtime.h"

namespace kdrt::cluster {

std::optional<TileWork> RemoteTiles::next() {
    while (!no_more_ && asks_.size() < kAhead) ask();
    if (asks_.empty()) return std::nullopt;
    wait_without_spinning(asks_.front().request, MPI_STATUS_IGNORE, 200);
    const TileMessage reply = asks_.front().reply;
    asks_.pop_front();
    complete_sends(false);
    if (reply.more <= 0) {
        no_more_ = true;
        if (reply.more < 0 && stop_code_ == 0) stop_code_ = -reply.more;
        return std::nullopt;
    }
    return TileWork{reply.frame, reply.rect};
}

void RemoteTiles::done(const TileWork& work, RenderResult&& r) {
    Packer p;
    p.put(static_cast<std::int32_t>(work.frame));
    p.put(work.rect);
    p.put(r.stats.rays);
    p.put_array(r.image.rgb);
    p.put_array(r.ids);
    p.put_array(r.hit_t);
    // What the frame's statistics report, for when rank 0 renders none of its tiles.
    p.put(r.stats.features);
    p.put_string(r.stats.opencl.kernel_options);
    p.put(r.stats.opencl.traversal_stack_bytes);
    p.put_string(r.stats.device_name);
    // This rank's warnings (its commit's come with its first tile): rank 0 reports them.
    p.put(static_cast<std::uint64_t>(r.warnings.size()));
    for (const std::string& w : r.warnings) p.put_string(w);
    sends_.push_back({std::move(p.bytes), MPI_REQUEST_NULL});
    Send& s = sends_.back();
    check_mpi(MPI_Isend(s.bytes.data(), static_cast<int>(s.bytes.size()), MPI_BYTE, 0, kTagResult, MPI_COMM_WORLD,
                        &s.request),
              "MPI_Isend");
}

void RemoteTiles::finish() {
    for (; !asks_.empty(); asks_.pop_front()) {
        wait_without_spinning(asks_.front().request);
        if (asks_.front().reply.more < 0 && stop_code_ == 0) stop_code_ = -asks_.front().reply.more;
    }
    no_more_ = true;
    complete_sends(true);
}
void RemoteTiles::ask() {
    Ask& a = asks_.emplace_back();  // a deque: the reply buffer does not move
    check_mpi(MPI_Irecv(&a.reply, sizeof a.reply, MPI_BYTE, 0, kTagTile, MPI_COMM_WORLD, &a.request), "MPI_Irecv");
    check_mpi(MPI_Send(nullptr, 0, MPI_BYTE, 0, kTagRequest, MPI_COMM_WORLD), "MPI_Send");
}
void RemoteTiles::complete_sends(bool all) {
    while (!sends_.empty()) {
        int done = 0;
        if (all)
            wait_without_spinning(sends_.front().request);
        else
            check_mpi(MPI_Test(&sends_.front().request, &done, MPI_STATUS_IGNORE), "MPI_Test");
        if (!all && !done) return;
        sends_.pop_front();
    }
}

}  // namespace kdrt::cluster
