// kdrt-render under mpirun: one job over all ranks. Rank 0 loads the scene,
// builds (or loads) the kd-tree on its first device, broadcasts the scene and
// the tree as bytes (kdrt/scene_wire.h, kdrt/kd_tree_io.h: the tree file
// format, checksum included), hands out tiles of every frame on demand while
// rendering tiles itself, and assembles the frames. The other ranks commit
// the scene with the tree given in memory and pull tiles until none are left.
//
// Failures end the job on every rank, never in a hang: a scene or option
// that rank 0 refuses stops the others at the broadcast; a rank that cannot
// open its device or fails to render is named by rank 0's message; a rank
// that dies is noticed by mpirun, which ends the job and names it.
#pragma once

#include "cluster/mpi_runtime.h"
#include "cluster/tile_loop.h"

#include <kdrt/render.h>
#include <kdrt/scene.h>

#include <functional>
#include <stdexcept>
#include <vector>

namespace kdrt::cluster {

struct JobSpec {
    RenderOptions options;  // as for one process; device: a name or list, "local-rank" allowed (rank_devices.h)
    int frames = 1;         // frames of the camera path
    FrameCamera camera;     // frame -> camera; frame 0 is the scene's
    int tile_width = 0, tile_height = 0;  // 0: 64 x 64 for one frame, whole frames for several
    // The exit status rank 0 gives an error (what the caller's main returns
    // for it), passed to every rank so that mpirun's status, the first
    // failing rank's, is the same whichever rank ends first. Unset: 1.
    std::function<int(const std::exception_ptr&)> exit_code_of;
};

// What rank 0 measured.
struct JobStats {
    int ranks = 1;
    double prepare_ms = 0.0;    // checking outputs, loading the scene
    double commit_ms = 0.0;     // committing on rank 0's first device: the tree build or load
    double serialize_ms = 0.0;  // scene and tree to bytes
    double broadcast_ms = 0.0;  // broadcasting them (once every rank is ready)
    std::uint64_t broadcast_bytes = 0;
    double render_ms = 0.0;     // from the broadcast's end to the last frame assembled
    double receive_ms = 0.0;    // receiving tile messages
    double assemble_ms = 0.0;   // copying tiles into frames
    double output_ms = 0.0;     // frame_done (writing the files)
    std::uint64_t tiles = 0;
    std::vector<DeviceShare> shares;  // every rank's devices, "rank N (host): device"
    // Per rank (0 for rank 0): from the broadcast's start to its first device committed, ready to render.
    std::vector<double> ready_ms;
    std::vector<double> decoded_ms;  // the part of ready_ms until the scene and tree were decoded
};

// A rank other than 0 after the job ended in error: rank 0 says why.
struct JobStopped : std::runtime_error {
    explicit JobStopped(int code = 1) : std::runtime_error("the cluster job stopped"), exit_code(code) {}
    int exit_code;  // rank 0's exit status (JobSpec::exit_code_of)
};

// Every rank calls it with the same spec. On rank 0, `prepare` checks the
// outputs and loads the scene (what it throws is rethrown here, after the
// other ranks were told to stop), and `frame_done` receives each complete
// frame (the scene with that frame's camera, the frame-sized result). Rank 0
// throws kdrt::Error naming the rank that failed; other ranks throw JobStopped.
void run_job(const MpiSession& session, const JobSpec& spec, const std::function<Scene()>& prepare,
             const std::function<void(int frame, const Scene& scene, RenderResult&& result)>& frame_done,
             JobStats& stats);

}  // namespace kdrt::cluster
