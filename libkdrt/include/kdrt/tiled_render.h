// One frame cut into tiles and rendered by several devices at once. Each
// device pulls the next tile when it has finished one, so a slow device takes
// fewer and none waits at a barrier while work remains. Every tile is bit for
// bit what its device renders for those pixels alone (FrameOptions::region),
// so devices of one kind give exactly the single-device picture.
#pragma once

#include <kdrt/commit_options.h>
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/export.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>
#include <kdrt/render_stats.h>
#include <kdrt/scene.h>

#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace kdrt {

struct TileSize {
    int width = 64, height = 64;
};

// The frame's tiles in the order they are handed out: rows of tiles from the
// top, each left to right; tiles at the right and bottom edges are clipped.
// Throws Error(InvalidArgument) for a non-positive frame or tile size.
KDRT_API std::vector<PixelRect> cut_into_tiles(int frame_width, int frame_height, TileSize tile = {});

// Called while device `device` (an index into render_tiles' scenes) renders
// `tile`, with the fraction of the tile done; returning false cancels.
using TileProgress = std::function<bool(std::size_t device, const PixelRect& tile, double fraction)>;

// Renders tiles until next_tile() returns nullopt: one thread per committed
// scene (one per device), each asking next_tile() for a tile, rendering it
// with frame.region set to it and handing the region-sized result to
// tile_done(device index, tile, result). render_tiles serialises the
// callbacks, tile_progress included (one call at a time, from the device
// threads). frame.progress and frame.region are not used.
// When a render or a callback throws (a tile_progress returning false makes
// its render throw Error(Cancelled)), the other devices abandon the tile at
// hand (within ~100 ms: its render is cancelled) and take no more, no
// callback is called again, and the first exception is rethrown once every
// device thread has ended. Returns one DeviceShare per scene, in order.
KDRT_API std::vector<DeviceShare> render_tiles(
    std::span<const CommittedScene> scenes, const FrameOptions& frame,
    const std::function<std::optional<PixelRect>()>& next_tile,
    const std::function<void(std::size_t device, const PixelRect& tile, RenderResult&& result)>& tile_done,
    const TileProgress& tile_progress = {});

// Opens every device a comma-separated list names: "cpu,opencl:0",
// "opencl:0,opencl:1", or "all" (the cpu device, then every OpenCL device of
// list_devices()). A name that opens no device, an empty list or name, or a
// device named twice (also as "opencl" and "opencl:0", or "all" and "cpu") is
// an Error(Device) naming it: two handles to one device split its cores or
// its queue and gain nothing. (MultiDeviceScene::commit itself takes any
// handles, two to one device included, as the tests do.)
// Note: PoCL is itself a CPU device; "cpu,opencl" on PoCL runs two renderers
// on the same cores, each with its own threads, and they compete for them.
KDRT_API std::vector<Device> open_devices(const std::string& list);

// A scene committed on several devices. The BVH or kd-tree is built (or
// loaded) once, on the first device, and given to the others in memory;
// TreeFiles::save is written once. A moved-from
// MultiDeviceScene throws kdrt::Error(InvalidArgument) from every call.
class KDRT_API MultiDeviceScene {
public:
    // Throws Error(InvalidArgument) for an empty device list.
    static MultiDeviceScene commit(std::span<const Device> devices, const Scene& scene,
                                   const CommitOptions& options = {});

    // As CommittedScene::update, on every device (a geometry change builds once).
    void update(const Scene& scene);

    // One frame in tiles handed out dynamically. The image, ids and hit_t are
    // the whole frame's (or frame.region's, cut into tiles itself); rays and
    // the devices' work (builds, compiles, uploads, launches) are summed over
    // the devices; stats.render_ms is the frame's wall time;
    // stats.device_shares says who did what; stats.device_name lists the
    // devices. frame.progress gets the fraction of pixels done (tiles in
    // flight counted by their own progress), serialised, from the device
    // threads; false cancels with Error(Cancelled) within ~100 ms.
    RenderResult render(const FrameOptions& frame = {}, TileSize tile = {}) const;

    std::span<const CommittedScene> scenes() const { return scenes_; }  // empty when moved from

private:
    explicit MultiDeviceScene(std::vector<CommittedScene> scenes) : scenes_(std::move(scenes)) {}
    std::vector<CommittedScene> scenes_;
};

}  // namespace kdrt
