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

}  // namespace

void run_rank0(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
               const std::function<void(int, const Scene&, RenderResult&&)>& frame_done, JobStats& stats) {
    stats.ranks = session.size();
    stats.ready_ms.assign(static_cast<std::size_t>(session.size()), 0.0);
    stats.decoded_ms.assign(static_cast<std::size_t>(session.size()), 0.0);
    explain_termination("kdrt-render: rank 0: ended by mpirun (a rank died, see mpirun's message naming it, "
                        "or the job was interrupted); the frame in progress was not written\n");
    Scene scene;
    std::vector<Device> devices;
    std::vector<CommittedScene> committed;
    std::exception_ptr setup_error;
    std::vector<std::uint8_t> payload;
    SetupHeader h;
    CommitStats commit_stats;
    std::optional<KdTreeStats> tree_stats;
    try {
        auto start = Clock::now();
        scene = prepare();
        stats.prepare_ms = ms_since(start);
        try {
            devices = open_rank_devices(spec.options.device, session.local_rank());
        } catch (const std::exception& e) {
            throw Error(ErrorCode::Device, session.name() + ": cannot open its device: " + e.what());
        }
        // The tree is made as a single process makes it (built, loaded, cached, saved). A BVH is
        // not sent: each rank builds its own, the same for any thread count.
        start = Clock::now();
        committed.push_back(CommittedScene::commit(devices[0], scene, spec.options.commit));
        stats.commit_ms = ms_since(start);
        commit_stats = committed[0].stats();
        if (const KdTree* tree = committed[0].tree()) tree_stats = kd_tree_stats(*tree, spec.options.commit.tree);
        start = Clock::now();
        payload = serialize_scene(scene);
        h.scene_bytes = static_cast<std::int64_t>(payload.size());
        if (const KdTree* tree = committed[0].tree()) {
            const std::vector<std::uint8_t> tree_bytes = serialize_kd_tree(*tree, committed[0].geometry_fingerprint());
            h.tree_bytes = static_cast<std::int64_t>(tree_bytes.size());
            payload.insert(payload.end(), tree_bytes.begin(), tree_bytes.end());
        }
        stats.serialize_ms = ms_since(start);
    } catch (...) {
        setup_error = std::current_exception();
    }

    // Every other rank says whether its devices opened.
    const auto own_picture = picture_options(spec);
    std::vector<std::string> hosts(static_cast<std::size_t>(session.size()));
    hosts[0] = session.host();
    std::string worker_failure;
    for (int received = 1; received < session.size();) {
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
        hosts[static_cast<std::size_t>(status.MPI_SOURCE)] = u.get_string();
        std::string message = u.get_string();
        const std::string rank_name =
            "rank " + std::to_string(status.MPI_SOURCE) + " (" + hosts[static_cast<std::size_t>(status.MPI_SOURCE)] + ")";
        std::vector<std::pair<std::string, std::string>> picture(u.get<std::uint64_t>());
        for (auto& [name, value] : picture) {
            name = u.get_string();
            value = u.get_string();
        }
        if (ok && picture != own_picture) {
            message = "its command line renders another picture than rank 0's:";
            for (std::size_t i = 0; i < std::min(picture.size(), own_picture.size()); ++i)
                if (picture[i] != own_picture[i])
                    message += " " + picture[i].first + " " + picture[i].second + " (rank 0: " + own_picture[i].second + ")";
            message += "; give every rank the same options (only --device and speed options may differ)";
        }
        if ((!ok || picture != own_picture) && worker_failure.empty()) worker_failure = rank_name + ": " + message;
        ++received;
    }

    const int frame_width = spec.options.frame.width ? spec.options.frame.width : scene.settings.width;
    const int frame_height = spec.options.frame.height ? spec.options.frame.height : scene.settings.height;
    h.frames = spec.frames;
    h.tile_width = spec.tile_width ? spec.tile_width : spec.frames > 1 ? frame_width : kDefaultTile;
    h.tile_height = spec.tile_height ? spec.tile_height : spec.frames > 1 ? frame_height : kDefaultTile;
    if (!setup_error) {
        // A tile's pixels go back to rank 0 in one MPI message, whose count is an int.
        const std::int64_t pixel_bytes = 12 + (spec.options.frame.want_ids ? 8 : 0);
        const std::int64_t max_pixels = (std::int64_t{INT32_MAX} - 4096) / pixel_bytes;
        const std::int64_t width = std::min<std::int64_t>(h.tile_width, frame_width);
        const std::int64_t height = std::min<std::int64_t>(h.tile_height, frame_height);
        if (width * height > max_pixels && spec.tile_width)
            setup_error = std::make_exception_ptr(Error(
                ErrorCode::InvalidArgument,
                "--tile " + std::to_string(spec.tile_width) + "x" + std::to_string(spec.tile_height) + ": a tile of " +
                    std::to_string(width) + "x" + std::to_string(height) + " pixels is " +
                    std::to_string(width * height * pixel_bytes) + " bytes to send to rank 0, more than an MPI "
                    "message holds (2 GiB); give smaller tiles"));
        else if (width * height > max_pixels)  // whole frames by default: as many full rows as fit
            h.tile_height = std::max<std::int64_t>(1, max_pixels / width);
    }
    h.ok = !setup_error && worker_failure.empty();
    h.exit_code = exit_code_for(spec, setup_error);
    auto start = Clock::now();
    broadcast_header(h);
    if (setup_error) std::rethrow_exception(setup_error);
    if (!worker_failure.empty()) throw Error(ErrorCode::Device, worker_failure);
    broadcast_payload(payload.data(), static_cast<std::int64_t>(payload.size()));
    stats.broadcast_ms = ms_since(start);
    stats.broadcast_bytes = payload.size();
    payload = {};

    // Rank 0 renders too, on a thread of its own; this thread serves the others.
    const RenderOptions options = tile_options(spec);
    const auto render_start = Clock::now();
    WorkQueue queue(cut_into_tiles(frame_width, frame_height, {static_cast<int>(h.tile_width), static_cast<int>(h.tile_height)}),
                    spec.frames);
    LocalTiles local(queue);
    std::vector<DeviceShare> local_shares;
    std::atomic<bool> local_done{false};
    std::optional<RenderResult> first_local;  // its statistics describe the frames
    std::optional<RenderResult> first_remote;  // or, when rank 0 renders none, another rank's first
    // Every rank's warnings, each reported once, with the next frame delivered.
    std::set<std::string> warnings_seen;
    std::vector<std::string> warnings_unreported;
    std::thread local_thread([&] {
        try {
            CommitOptions others = options.commit;
            if (const KdTree* tree = committed[0].tree())
                others.tree_files.in_memory = std::make_shared<const KdTree>(*tree);
            auto commit = [&](std::size_t d) {
                return d == 0 ? committed[0] : CommittedScene::commit(devices[d], scene, others);
            };
            local_shares = run_tile_loop(devices.size(), commit, scene, options.frame, spec.camera, local);
        } catch (const std::exception& e) {
            queue.abort(rank_error(session.name(), e.what()));
        }
        local_done = true;
    });

    FrameAssembler assembler(frame_width, frame_height, options.frame.want_ids);
    int frames_delivered = 0;
    auto deliver = [&](int frame, RenderResult&& r) {
        const auto t = Clock::now();
        try {
            Scene frame_scene = scene;
            frame_scene.camera = spec.camera(scene.camera, frame);
            r.stats.device_name = std::to_string(session.size()) + " ranks";
            r.stats.build_ms = commit_stats.build_ms;
            r.stats.compile_ms = commit_stats.compile_ms;
            r.stats.upload_ms = commit_stats.upload_ms;
            r.stats.tree_loaded = commit_stats.tree_loads > 0;
            r.stats.tree_stats = tree_stats;
            r.stats.render_ms = stats.render_ms;
            ++frames_delivered;
            frame_done(frame, frame_scene, std::move(r));
            if (frames_delivered == spec.frames)  // a rank that dies now costs no output
                explain_termination("kdrt-render: rank 0: ended by mpirun (a rank died, see mpirun's message naming "
                                    "it, or the job was interrupted) after every frame was written\n");
        } catch (...) {
            queue.abort(std::current_exception());
        }
        stats.output_ms += ms_since(t);
    };
    auto assemble = [&](const TileWork& work, RenderResult&& tile, bool local_tile) {
        if (queue.aborted()) return;
        ++stats.tiles;
        for (const std::string& w : tile.warnings) {
            const std::string named = local_tile ? session.name() + ": " + w : w;  // remote ones are named already
            if (warnings_seen.insert(named).second) warnings_unreported.push_back(named);
        }
        if (!first_local && local_tile) {
            first_local = RenderResult{};
            first_local->stats.features = tile.stats.features;
            first_local->stats.opencl.kernel_options = tile.stats.opencl.kernel_options;
            first_local->stats.device_name = tile.stats.device_name;
            first_local->stats.opencl.launches = tile.stats.opencl.launches;
            first_local->stats.opencl.kernel_resources = tile.stats.opencl.kernel_resources;
            first_local->stats.opencl.traversal_stack_bytes = tile.stats.opencl.traversal_stack_bytes;
        }
        const auto t = Clock::now();
        std::optional<RenderResult> frame = assembler.add(work.frame, work.rect, tile);
        stats.assemble_ms += ms_since(t);
        if (frame) {
            stats.render_ms = ms_since(render_start);
            if (first_local) {
                frame->stats.features = first_local->stats.features;
                frame->stats.opencl.kernel_options = first_local->stats.opencl.kernel_options;
                frame->stats.opencl.kernel_resources = first_local->stats.opencl.kernel_resources;
                frame->stats.opencl.traversal_stack_bytes = first_local->stats.opencl.traversal_stack_bytes;
            } else if (first_remote) {
                frame->stats.features = first_remote->stats.features;
                frame->stats.opencl.kernel_options = first_remote->stats.opencl.kernel_options;
                frame->stats.opencl.traversal_stack_bytes = first_remote->stats.opencl.traversal_stack_bytes;
            }
            frame->warnings = std::move(warnings_unreported);
            warnings_unreported.clear();
            deliver(work.frame, std::move(*frame));
        }
    };

    auto assemble_local = [&](const TileWork& work, RenderResult&& tile) {
        try {
            assemble(work, std::move(tile), true);
        } catch (const std::exception& e) {
            queue.abort(rank_error(session.name(), e.what()));
        }
    };
    // An MPI failure here must not leave the local thread running (std::terminate).
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

    int workers_left = session.size() - 1;
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
            const int from = status.MPI_SOURCE;
            const std::string rank_name = "rank " + std::to_string(from) + " (" + hosts[static_cast<std::size_t>(from)] + ")";
            const auto t = Clock::now();
            const std::vector<std::uint8_t> bytes = receive_bytes(status);
            stats.receive_ms += ms_since(t);
            Unpacker u(bytes);
            if (status.MPI_TAG == kTagRequest) {
                TileMessage reply;
                if (std::optional<TileWork> work = queue.take()) {
                    reply.more = 1;
                    reply.frame = work->frame;
                    reply.rect = work->rect;
                } else {
                    reply.more = queue.aborted() ? -exit_code_for(spec, queue.error()) : 0;
                }
                check_mpi(MPI_Send(&reply, sizeof reply, MPI_BYTE, from, kTagTile, MPI_COMM_WORLD), "MPI_Send");
            } else if (status.MPI_TAG == kTagResult) {
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
                const std::string device_name = u.get_string();
                const auto warning_count = u.get<std::uint64_t>();
                for (std::uint64_t i = 0; i < warning_count; ++i) tile.warnings.push_back(rank_name + ": " + u.get_string());
                if (!first_remote) {
                    first_remote = RenderResult{};
                    first_remote->stats.features = tile.stats.features;
                    first_remote->stats.opencl.kernel_options = tile.stats.opencl.kernel_options;
                    first_remote->stats.opencl.traversal_stack_bytes = tile.stats.opencl.traversal_stack_bytes;
                    first_remote->stats.device_name = device_name;
                }
                try {
                    assemble(work, std::move(tile), false);
                } catch (const std::exception& e) {
                    queue.abort(rank_error(rank_name, e.what()));
                }
            } else if (status.MPI_TAG == kTagFailed) {
                queue.abort(rank_error(rank_name, u.get_string()));
            } else if (status.MPI_TAG == kTagFinal) {
                stats.decoded_ms[static_cast<std::size_t>(from)] = u.get<double>();
                stats.ready_ms[static_cast<std::size_t>(from)] = u.get<double>();
                const auto n = u.get<std::uint64_t>();
                for (std::uint64_t i = 0; i < n; ++i) stats.shares.push_back(get_share(u));
                --workers_left;
            }
        }
        if (busy) {
            sleep_us = 2;
        } else {
            std::this_thread::sleep_for(std::chrono::microseconds(sleep_us));
            sleep_us = std::min(sleep_us * 2, 500);
        }
    }
    local_thread.join();
    for (auto& [work, r] : local.take_results()) assemble_local(work, std::move(r));
    if (std::exception_ptr error = queue.error()) std::rethrow_exception(error);
    if (frames_delivered != spec.frames)
        throw Error(ErrorCode::Device, "cluster: " + std::to_string(spec.frames - frames_delivered) +
                                           " frames were not completed (tiles lost)");
    name_shares(local_shares, session.name());
    stats.shares.insert(stats.shares.begin(), local_shares.begin(), local_shares.end());
}

}  // namespace kdrt::cluster::detail
