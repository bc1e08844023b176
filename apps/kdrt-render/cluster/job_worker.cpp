// The other ranks' side of a cluster job: say whether the devices opened,
// take the scene and tree from the broadcast, render what rank 0 hands out.
#include "cluster/job_parts.h"
#include "cluster/mpi_messages.h"
#include "cluster/rank_devices.h"
#include "cluster/remote_tiles.h"

#include <kdrt/committed_scene.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/scene_wire.h>

#include <memory>
#include <mutex>

namespace kdrt::cluster::detail {

void run_worker(const MpiSession& session, const JobSpec& spec) {
    std::vector<Device> devices;
    std::string failure;
    try {
        devices = open_rank_devices(spec.options.device, session.local_rank());
    } catch (const std::exception& e) {
        failure = std::string("cannot open its device: ") + e.what();
    }
    Packer hello;
    hello.put<std::uint8_t>(failure.empty());
    hello.put_string(session.host());
    hello.put_string(failure);
    const auto picture = picture_options(spec);
    hello.put<std::uint64_t>(picture.size());
    for (const auto& [name, value] : picture) {
        hello.put_string(name);
        hello.put_string(value);
    }
    send_bytes(hello.bytes, 0, kTagHello);

    SetupHeader h;
    broadcast_header(h);
    if (!h.ok) throw JobStopped(static_cast<int>(h.exit_code));
    const auto payload_start = Clock::now();
    double ready_ms = 0.0;   // broadcast, decoding and commit: until this rank can render
    double decoded_ms = 0.0;  // broadcast and decoding
    std::vector<std::uint8_t> payload(static_cast<std::size_t>(h.scene_bytes + h.tree_bytes));
    broadcast_payload(payload.data(), static_cast<std::int64_t>(payload.size()));

    std::vector<DeviceShare> shares;
    RemoteTiles tiles;
    try {
        const Scene scene = deserialize_scene(payload.data(), static_cast<std::size_t>(h.scene_bytes), "the broadcast scene");
        RenderOptions options = tile_options(spec);
        if (h.tree_bytes > 0)
            options.commit.tree_files.in_memory = std::make_shared<const KdTree>(
                deserialize_kd_tree(payload.data() + h.scene_bytes, static_cast<std::size_t>(h.tree_bytes),
                                    geometry_fingerprint(scene), "the broadcast kd-tree"));
        payload = {};
        decoded_ms = ms_since(payload_start);
        std::mutex ready_mutex;
        auto commit = [&](std::size_t d) {
            CommittedScene committed = CommittedScene::commit(devices[d], scene, options.commit);
            std::lock_guard lock(ready_mutex);
            if (ready_ms == 0.0) ready_ms = ms_since(payload_start);  // the first device ready
            return committed;
        };
        shares = run_tile_loop(devices.size(), commit, scene, options.frame, spec.camera, tiles);
        tiles.finish();
    } catch (const std::exception& e) {
        tiles.finish();
        Packer p;
        p.put_string(e.what());
        send_bytes(p.bytes, 0, kTagFailed);
        failure = e.what();
    }
    name_shares(shares, session.name());
    Packer final;
    final.put(decoded_ms);
    final.put(ready_ms);
    final.put<std::uint64_t>(shares.size());
    for (const DeviceShare& s : shares) put_share(final, s);
    send_bytes(final.bytes, 0, kTagFinal);
    if (!failure.empty()) throw JobStopped();
    if (tiles.stopped()) throw JobStopped(tiles.stop_code());
}

}  // namespace kdrt::cluster::detail
