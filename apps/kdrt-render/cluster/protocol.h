// The messages between rank 0 and the other ranks (all point to point, MPI
// tags below, byte buffers in host order: a job runs one build of
// kdrt-render on hosts of one byte order).
//
//   start-up   worker -> 0   Hello     its devices opened, or why not
//              0 -> all      Ibcast    SetupHeader, then the scene (kdrt/scene_wire.h)
//                                      and the tree (kdrt/kd_tree_io.h) bytes, or "stop"
//   render     worker -> 0   Request   one per device thread wanting a tile
//              0 -> worker   Tile      a frame's rectangle, or "no more"
//              worker -> 0   Result    a tile's pixels, ids and ray counts
//              worker -> 0   Failed    why it stopped (commit, render)
//   end        worker -> 0   Final     how long it took to decode and to be ready, what each of its devices did
//                                      (after its last Tile "no more")
//
// Every worker ends with Final, after a failure too, so rank 0 knows when
// all are done without a barrier.
#pragma once

#include <kdrt/frame_options.h>
#include <kdrt/render_stats.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace kdrt::cluster {

enum Tag : int { kTagHello = 1, kTagRequest, kTagTile, kTagResult, kTagFailed, kTagFinal };

// Broadcast by rank 0 after it loaded the scene and made the tree.
struct SetupHeader {
    std::int64_t ok = 0;           // 0: stop, every rank exits with exit_code (rank 0 prints why)
    std::int64_t exit_code = 1;    // rank 0's exit status for the failure (2: a usage error)
    std::int64_t scene_bytes = 0;
    std::int64_t tree_bytes = 0;   // 0: no tree (Traversal::None)
    std::int64_t frames = 1;
    std::int64_t tile_width = 0, tile_height = 0;
};

// Rank 0's answer to a Request.
struct TileMessage {
    std::int32_t more = 0;  // 0: no more tiles, the device thread stops; < 0: the job failed, -more is rank 0's exit status
    std::int32_t frame = 0;
    PixelRect rect;
};

// A byte buffer written and read field by field.
class Packer {
public:
    std::vector<std::uint8_t> bytes;
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
        bytes.insert(bytes.end(), p, p + sizeof(T));
    }
    void put_string(const std::string& s) {
        put<std::uint64_t>(s.size());
        bytes.insert(bytes.end(), s.begin(), s.end());
    }
    template <class T>
    void put_array(const std::vector<T>& v) {
        put<std::uint64_t>(v.size());
        const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
        bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
    }
};

class Unpacker {
public:
    Unpacker(const std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}
    template <class T>
    T get() {
        T v;
        need(sizeof(T));
        std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    std::string get_string() {
        const auto n = get<std::uint64_t>();
        need(n);
        std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
        pos_ += n;
        return s;
    }
    template <class T>
    std::vector<T> get_array() {
        const auto n = get<std::uint64_t>();
        if (n > (bytes_.size() - pos_) / sizeof(T)) throw std::runtime_error("cluster message: truncated array");
        std::vector<T> v(n);
        std::memcpy(v.data(), bytes_.data() + pos_, n * sizeof(T));
        pos_ += n * sizeof(T);
        return v;
    }

private:
    void need(std::uint64_t n) const {
        if (n > bytes_.size() - pos_) throw std::runtime_error("cluster message: truncated");
    }
    const std::vector<std::uint8_t>& bytes_;
    std::size_t pos_ = 0;
};

// A DeviceShare in a Final message.
inline void put_share(Packer& p, const DeviceShare& s) {
    p.put_string(s.device_name);
    p.put(s.tiles);
    p.put(s.pixels);
    p.put(s.busy_ms);
    p.put(s.rays);
}
inline DeviceShare get_share(Unpacker& u) {
    DeviceShare s;
    s.device_name = u.get_string();
    s.tiles = u.get<std::uint64_t>();
    s.pixels = u.get<std::uint64_t>();
    s.busy_ms = u.get<double>();
    s.rays = u.get<RayCounts>();
    return s;
}

}  // namespace kdrt::cluster
