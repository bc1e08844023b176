// Rank 0's side of a cluster job: load, make the tree, broadcast, render
// tiles on its own thread while this one serves the others and assembles.
#include "cluster/frame_assembler.h"
#include "cluster/job_parts.h"
#include "cluster/mpi_messages.h"
#include "cluster/rank_devices.h"
#include "cluster/work_queue.h"

#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/scene_wire.h>
#include <kdrt/tiled_render.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <set>
#include <thread>

namespace kdrt::cluster::detail {

namespace {

constexpr int kDefaultTile = 64;

std::exception_ptr rank_error(const std::string& rank_name, const std::string& what) {
    return std::make_exception_ptr(Error(ErrorCode::Device, rank_name + ": " + what));
}

// The statistics a frame's result reports that tiles carry (features, kernels),
// from rank 0's first tile, else from another rank's.
struct FrameDescription {
    std::optional<RenderResult> local, remote;

    void describe(RenderResult& frame) const {
        if (local) {
            frame.stats.features = local->stats.features;
            frame.stats.opencl.kernel_options = local->stats.opencl.kernel_options;
            frame.stats.opencl.kernel_resources = local->stats.opencl.kernel_resources;
            frame.stats.opencl.traversal_stack_bytes = local->stats.opencl.traversal_stack_bytes;
        } else if (remote) {
            frame.stats.features = remote->stats.features;
            frame.stats.opencl.kernel_options = remote->stats.opencl.kernel_options;
            frame.stats.opencl.traversal_stack_bytes = remote->stats.opencl.traversal_stack_bytes;
        }
    }
    static RenderResult of(const RenderResult& tile) {
        RenderResult d;
        d.stats.features = tile.stats.features;
        d.stats.opencl.kernel_options = tile.stats.opencl.kernel_options;
        d.stats.device_name = tile.stats.device_name;
        d.stats.opencl.launches = tile.stats.opencl.launches;
        d.stats.opencl.kernel_resources = tile.stats.opencl.kernel_resources;
        d.stats.opencl.traversal_stack_bytes = tile.stats.opencl.traversal_stack_bytes;
        return d;
    }
};

// A tile's result as another rank sent it (kTagResult).
std::pair<TileWork, RenderResult> unpack_result(Unpacker& u, const std::string& rank_name, std::string& device_name) {
    TileWork work;
    work.frame = u.get<std::int32_t>();
    work.rect = u.get<PixelRect>();
    RenderResult tile;
    tile.stats.rays = u.get<RayCounts>();
    tile.image.width = work.rect.width;
    tile.image.height = work.rect.height;
    tile.image.rgb = u.get_array<float>();
    tile.ids = u.get_array<std::int32_t>();
    tile.hit_t = u.get_array<float>();
    tile.stats.features = u.get<SceneFeatures>();
    tile.stats.opencl.kernel_options = u.get_string();
    tile.stats.opencl.traversal_stack_bytes = u.get<std::uint64_t>();
    device_name = u.get_string();
    const auto warning_count = u.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < warning_count; ++i) tile.warnings.push_back(rank_name + ": " + u.get_string());
    return {work, std::move(tile)};
}

class Rank0Job {
public:
    Rank0Job(const MpiSession& session, const JobSpec& spec,
             const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats)
        : session_(session), spec_(spec), frame_done_(frame_done), stats_(stats),
          hosts_(static_cast<std::size_t>(session.size())) {
        stats_.ranks = session.size();
        stats_.ready_ms.assign(static_cast<std::size_t>(session.size()), 0.0);
        stats_.decoded_ms.assign(static_cast<std::size_t>(session.size()), 0.0);
        hosts_[0] = session.host();
    }

    void run(const std::function<Scene()>& prepare) {
        explain_termination("kdrt-render: rank 0: ended by mpirun (a rank died, see mpirun's message naming it, "
                            "or the job was interrupted); the frame in progress was not written\n");
        set_up(prepare);
        collect_hellos();
        choose_tiles();
        broadcast_setup();
        render_and_serve();
    }

private:
    std::string rank_name(int rank) const {
        return "rank " + std::to_string(rank) + " (" + hosts_[static_cast<std::size_t>(rank)] + ")";
    }

    // The scene loaded, rank 0's devices opened, the tree made as a single
    // process makes it (built, loaded, cached, saved), all serialized. A BVH
    // is not sent: each rank builds its own, the same for any thread count. A
    // failure is kept to tell the other ranks at the broadcast.
    void set_up(const std::function<Scene()>& prepare) {
        try {
            auto start = Clock::now();
            scene_ = prepare();
            stats_.prepare_ms = ms_since(start);
            try {
                devices_ = open_rank_devices(spec_.options.device, session_.local_rank());
            } catch (const std::exception& e) {
                throw Error(ErrorCode::Device, session_.name() + ": cannot open its device: " + e.what());
            }
            start = Clock::now();
            committed_.push_back(CommittedScene::commit(devices_[0], scene_, spec_.options.commit));
            stats_.commit_ms = ms_since(start);
            commit_stats_ = committed_[0].stats();
            if (const KdTree* tree = committed_[0].tree()) tree_stats_ = kd_tree_stats(*tree, spec_.options.commit.tree);
            bvh_stats_ = committed_[0].bvh_stats();
            serialize();
        } catch (...) {
            setup_error_ = std::current_exception();
        }
    }

    void serialize() {
        const auto start = Clock::now();
        payload_ = serialize_scene(scene_);
        header_.scene_bytes = static_cast<std::int64_t>(payload_.size());
        if (const KdTree* tree = committed_[0].tree()) {
            const std::vector<std::uint8_t> tree_bytes = serialize_kd_tree(*tree, committed_[0].geometry_fingerprint());
            header_.tree_bytes = static_cast<std::int64_t>(tree_bytes.size());
            payload_.insert(payload_.end(), tree_bytes.begin(), tree_bytes.end());
        }
        stats_.serialize_ms = ms_since(start);
    }

    // Every other rank says whether its devices opened, and which picture its options render.
    void collect_hellos() {
        const auto own_picture = picture_options(spec_);
        for (int received = 1; received < session_.size();) {
            MPI_Status status;
            int flag = 0;
            check_mpi(MPI_Iprobe(MPI_ANY_SOURCE, kTagHello, MPI_COMM_WORLD, &flag, &status), "MPI_Iprobe");
            if (!flag) {
                std::this_thread::sleep_for(std::chrono::microseconds(500));
                continue;
            }
            const std::vector<std::uint8_t> bytes = receive_bytes(status);
            Unpacker u(bytes);
            const bool ok = u.get<std::uint8_t>() != 0;
            hosts_[static_cast<std::size_t>(status.MPI_SOURCE)] = u.get_string();
            std::string message = u.get_string();
            std::vector<std::pair<std::string, std::string>> picture(u.get<std::uint64_t>());
            for (auto& [name, value] : picture) {
                name = u.get_string();
                value = u.get_string();
            }
            if (ok && picture != own_picture) message = picture_difference(picture, own_picture);
            if ((!ok || picture != own_picture) && worker_failure_.empty())
                worker_failure_ = rank_name(status.MPI_SOURCE) + ": " + message;
            ++received;
        }
    }

    static std::string picture_difference(const std::vector<std::pair<std::string, std::string>>& picture,
                                          const std::vector<std::pair<std::string, std::string>>& own) {
        std::string message = "its command line renders another picture than rank 0's:";
        for (std::size_t i = 0; i < std::min(picture.size(), own.size()); ++i)
            if (picture[i] != own[i])
                message += " " + picture[i].first + " " + picture[i].second + " (rank 0: " + own[i].second + ")";
        return message + "; give every rank the same options (only --device and speed options may differ)";
    }

    // Tiles of --tile, else 64 x 64 for one frame and whole frames for several.
    void choose_tiles() {
        frame_width_ = spec_.options.frame.width ? spec_.options.frame.width : scene_.settings.width;
        frame_height_ = spec_.options.frame.height ? spec_.options.frame.height : scene_.settings.height;
        header_.frames = spec_.frames;
        header_.tile_width = spec_.tile_width ? spec_.tile_width : spec_.frames > 1 ? frame_width_ : kDefaultTile;
        header_.tile_height = spec_.tile_height ? spec_.tile_height : spec_.frames > 1 ? frame_height_ : kDefaultTile;
        if (setup_error_) return;
        // A tile's pixels go back to rank 0 in one MPI message, whose count is an int.
        const std::int64_t pixel_bytes = 12 + (spec_.options.frame.want_ids ? 8 : 0);
        const std::int64_t max_pixels = (std::int64_t{INT32_MAX} - 4096) / pixel_bytes;
        const std::int64_t width = std::min<std::int64_t>(header_.tile_width, frame_width_);
        const std::int64_t height = std::min<std::int64_t>(header_.tile_height, frame_height_);
        if (width * height > max_pixels && spec_.tile_width)
            setup_error_ = std::make_exception_ptr(Error(
                ErrorCode::InvalidArgument,
                "--tile " + std::to_string(spec_.tile_width) + "x" + std::to_string(spec_.tile_height) + ": a tile of " +
                    std::to_string(width) + "x" + std::to_string(height) + " pixels is " +
                    std::to_string(width * height * pixel_bytes) + " bytes to send to rank 0, more than an MPI "
                    "message holds (2 GiB); give smaller tiles"));
        else if (width * height > max_pixels)  // whole frames by default: as many full rows as fit
            header_.tile_height = std::max<std::int64_t>(1, max_pixels / width);
    }

    // The header tells every rank to go on or stop (with rank 0's status); then the bytes.
    void broadcast_setup() {
        header_.ok = !setup_error_ && worker_failure_.empty();
        header_.exit_code = exit_code_for(spec_, setup_error_);
        const auto start = Clock::now();
        broadcast_header(header_);
        if (setup_error_) std::rethrow_exception(setup_error_);
        if (!worker_failure_.empty()) throw Error(ErrorCode::Device, worker_failure_);
        broadcast_payload(payload_.data(), static_cast<std::int64_t>(payload_.size()));
        stats_.broadcast_ms = ms_since(start);
        stats_.broadcast_bytes = payload_.size();
        payload_ = {};
    }

    // Rank 0 renders too, on a thread of its own; this thread serves the others.
    void render_and_serve() {
        const RenderOptions options = tile_options(spec_);
        render_start_ = Clock::now();
        WorkQueue queue(cut_into_tiles(frame_width_, frame_height_,
                                       {static_cast<int>(header_.tile_width), static_cast<int>(header_.tile_height)}),
                        spec_.frames);
        queue_ = &queue;
        LocalTiles local(queue);
        FrameAssembler assembler(frame_width_, frame_height_, options.frame.want_ids);
        assembler_ = &assembler;
        std::vector<DeviceShare> local_shares;
        std::atomic<bool> local_done{false};
        std::thread local_thread([&] {
            try {
                CommitOptions others = options.commit;
                if (const KdTree* tree = committed_[0].tree())
                    others.tree_files.in_memory = std::make_shared<const KdTree>(*tree);
                auto commit = [&](std::size_t d) {
                    return d == 0 ? committed_[0] : CommittedScene::commit(devices_[d], scene_, others);
                };
                local_shares = run_tile_loop(devices_.size(), commit, scene_, options.frame, spec_.camera, local);
            } catch (const std::exception& e) {
                queue.abort(rank_error(session_.name(), e.what()));
            }
            local_done = true;
        });
        // An MPI failure while serving must not leave the local thread running (std::terminate).
        struct JoinOnExit {
            WorkQueue& queue;
            std::thread& thread;
            ~JoinOnExit() {
                if (thread.joinable()) {
                    queue.abort(std::make_exception_ptr(Error(ErrorCode::Device, "cluster: rank 0 stopped serving")));
                    thread.join();
                }
            }
        } join_on_exit{queue, local_thread};
        serve(local, local_done);
        local_thread.join();
        for (auto& [work, r] : local.take_results()) assemble_local(work, std::move(r));
        finish(local_shares);
    }

    // Until every other rank has sent its Final and rank 0's thread is done.
    void serve(LocalTiles& local, const std::atomic<bool>& local_done) {
        int workers_left = session_.size() - 1;
        int sleep_us = 2;
        while (workers_left > 0 || !local_done) {
            bool busy = false;
            for (auto& [work, r] : local.take_results()) {
                assemble_local(work, std::move(r));
                busy = true;
            }
            MPI_Status status;
            int flag = 0;
            check_mpi(MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status), "MPI_Iprobe");
            if (flag) {
                busy = true;
                if (handle_message(status)) --workers_left;
            }
            if (busy) {
                sleep_us = 2;
            } else {
                std::this_thread::sleep_for(std::chrono::microseconds(sleep_us));
                sleep_us = std::min(sleep_us * 2, 500);
            }
        }
    }

    // One message from another rank; true for its Final.
    bool handle_message(const MPI_Status& status) {
        const int from = status.MPI_SOURCE;
        const auto t = Clock::now();
        const std::vector<std::uint8_t> bytes = receive_bytes(status);
        stats_.receive_ms += ms_since(t);
        Unpacker u(bytes);
        switch (status.MPI_TAG) {
            case kTagRequest: answer_request(from); return false;
            case kTagResult: assemble_remote(u, from); return false;
            case kTagFailed: queue_->abort(rank_error(rank_name(from), u.get_string())); return false;
            case kTagFinal:
                stats_.decoded_ms[static_cast<std::size_t>(from)] = u.get<double>();
                stats_.ready_ms[static_cast<std::size_t>(from)] = u.get<double>();
                for (std::uint64_t i = 0, n = u.get<std::uint64_t>(); i < n; ++i) stats_.shares.push_back(get_share(u));
                return true;
            default: return false;
        }
    }

    void answer_request(int from) {
        TileMessage reply;
        if (std::optional<TileWork> work = queue_->take()) {
            reply.more = 1;
            reply.frame = work->frame;
            reply.rect = work->rect;
        } else {
            reply.more = queue_->aborted() ? -exit_code_for(spec_, queue_->error()) : 0;
        }
        check_mpi(MPI_Send(&reply, sizeof reply, MPI_BYTE, from, kTagTile, MPI_COMM_WORLD), "MPI_Send");
    }

    void assemble_remote(Unpacker& u, int from) {
        std::string device_name;
        auto [work, tile] = unpack_result(u, rank_name(from), device_name);
        if (!description_.remote) {
            description_.remote = FrameDescription::of(tile);
            description_.remote->stats.device_name = device_name;
        }
        try {
            assemble(work, std::move(tile), false);
        } catch (const std::exception& e) {
            queue_->abort(rank_error(rank_name(from), e.what()));
        }
    }

    void assemble_local(const TileWork& work, RenderResult&& tile) {
        try {
            assemble(work, std::move(tile), true);
        } catch (const std::exception& e) {
            queue_->abort(rank_error(session_.name(), e.what()));
        }
    }

    // A tile into its frame; a complete frame is delivered with every rank's
    // warnings not yet reported, each once.
    void assemble(const TileWork& work, RenderResult&& tile, bool local_tile) {
        if (queue_->aborted()) return;
        ++stats_.tiles;
        for (const std::string& w : tile.warnings) {
            const std::string named = local_tile ? session_.name() + ": " + w : w;  // remote ones are named already
            if (warnings_seen_.insert(named).second) warnings_unreported_.push_back(named);
        }
        if (!description_.local && local_tile) description_.local = FrameDescription::of(tile);
        const auto t = Clock::now();
        std::optional<RenderResult> frame = assembler_->add(work.frame, work.rect, tile);
        stats_.assemble_ms += ms_since(t);
        if (!frame) return;
        stats_.render_ms = ms_since(render_start_);
        description_.describe(*frame);
        frame->warnings = std::exchange(warnings_unreported_, {});
        deliver(work.frame, std::move(*frame));
    }

    void deliver(int frame, RenderResult&& r) {
        const auto t = Clock::now();
        try {
            Scene frame_scene = scene_;
            frame_scene.camera = spec_.camera(scene_.camera, frame);
            r.stats.device_name = std::to_string(session_.size()) + " ranks";
            r.stats.build_ms = commit_stats_.build_ms;
            r.stats.compile_ms = commit_stats_.compile_ms;
            r.stats.upload_ms = commit_stats_.upload_ms;
            r.stats.tree_loaded = commit_stats_.tree_loads > 0;
            r.stats.tree_stats = tree_stats_;
            r.stats.bvh_stats = bvh_stats_;
            r.stats.render_ms = stats_.render_ms;
            ++frames_delivered_;
            frame_done_(frame, frame_scene, std::move(r));
            if (frames_delivered_ == spec_.frames)  // a rank that dies now costs no output
                explain_termination("kdrt-render: rank 0: ended by mpirun (a rank died, see mpirun's message naming "
                                    "it, or the job was interrupted) after every frame was written\n");
        } catch (...) {
            queue_->abort(std::current_exception());
        }
        stats_.output_ms += ms_since(t);
    }

    void finish(std::vector<DeviceShare>& local_shares) {
        if (std::exception_ptr error = queue_->error()) std::rethrow_exception(error);
        if (frames_delivered_ != spec_.frames)
            throw Error(ErrorCode::Device, "cluster: " + std::to_string(spec_.frames - frames_delivered_) +
                                               " frames were not completed (tiles lost)");
        name_shares(local_shares, session_.name());
        stats_.shares.insert(stats_.shares.begin(), local_shares.begin(), local_shares.end());
    }

    const MpiSession& session_;
    const JobSpec& spec_;
    const std::function<void(int, const Scene&, RenderResult&&)>& frame_done_;
    JobStats& stats_;
    std::vector<std::string> hosts_;

    Scene scene_;
    std::vector<Device> devices_;
    std::vector<CommittedScene> committed_;
    CommitStats commit_stats_;
    std::optional<KdTreeStats> tree_stats_;
    std::optional<BvhStats> bvh_stats_;
    std::exception_ptr setup_error_;
    std::string worker_failure_;
    std::vector<std::uint8_t> payload_;
    SetupHeader header_;
    int frame_width_ = 0, frame_height_ = 0;

    Clock::time_point render_start_;
    WorkQueue* queue_ = nullptr;
    FrameAssembler* assembler_ = nullptr;
    FrameDescription description_;
    std::set<std::string> warnings_seen_;
    std::vector<std::string> warnings_unreported_;
    int frames_delivered_ = 0;
};

}  // namespace

void run_rank0(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
               const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats) {
    Rank0Job(session, spec, frame_done, stats).run(prepare);
}

}  // namespace kdrt::cluster::detail
