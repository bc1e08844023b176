// A rank's devices rendering tiles from a source: one thread per committed
// scene, each asking the source for a tile when it has finished one, so a
// fast device takes more. Like kdrt::render_tiles, but a tile names its frame
// too and each device moves its own committed scene to that frame's camera
// (CommittedScene::update: no rebuild, the geometry is the same), so frames
// of a camera path are units of work as well as tiles.
#pragma once

#include <kdrt/committed_scene.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>
#include <kdrt/scene.h>

#include <functional>
#include <optional>
#include <vector>

namespace kdrt::cluster {

struct TileWork {
    int frame = 0;
    PixelRect rect;
};

// Where tiles come from and where they go. Calls are serialised (one at a
// time, from the device threads).
class TileSource {
public:
    virtual ~TileSource() = default;
    virtual std::optional<TileWork> next() = 0;
    virtual void done(const TileWork& work, RenderResult&& result) = 0;
};

// The camera of a frame, from the scene's.
using FrameCamera = std::function<Camera(const Camera& scene_camera, int frame)>;

// Commits the scene (frame 0's camera) on device `d`.
using CommitOnDevice = std::function<CommittedScene(std::size_t d)>;

// Renders until the source has no more, with one thread per device, each
// starting as soon as its own commit is done (an OpenCL compile does not hold
// back the cpu device). When a commit, a render or the source throws, the
// other devices finish the tile at hand and take no more, and the first
// exception is rethrown. One DeviceShare per device, named by its device.
std::vector<DeviceShare> run_tile_loop(std::size_t devices, const CommitOnDevice& commit, const Scene& scene,
                                       const FrameOptions& frame, const FrameCamera& camera, TileSource& source);

}  // namespace kdrt::cluster
