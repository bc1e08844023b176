// Rank 0's supply of tiles: every tile of every frame in order, taken by its
// own devices directly and handed to the other ranks on request.
#pragma once

#include "cluster/tile_loop.h"

#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

namespace kdrt::cluster {

// The work of the whole job, tile by tile, shared by rank 0's own devices and
// the requests of the others.
class WorkQueue {
public:
    WorkQueue(std::vector<PixelRect> tiles, int frames) : tiles_(std::move(tiles)), total_(tiles_.size() * frames) {}

    std::optional<TileWork> take() {
        std::lock_guard lock(mutex_);
        if (aborted_ || next_ >= total_) return std::nullopt;
        const std::size_t i = next_++;
        return TileWork{static_cast<int>(i / tiles_.size()), tiles_[i % tiles_.size()]};
    }
    // The first failure stops the handing out; later ones are dropped.
    void abort(std::exception_ptr error) {
        std::lock_guard lock(mutex_);
        if (!aborted_) error_ = error;
        aborted_ = true;
    }
    bool aborted() {
        std::lock_guard lock(mutex_);
        return aborted_;
    }
    std::exception_ptr error() {
        std::lock_guard lock(mutex_);
        return error_;
    }

private:
    std::mutex mutex_;
    std::vector<PixelRect> tiles_;
    std::size_t total_, next_ = 0;
    bool aborted_ = false;
    std::exception_ptr error_;
};

// Rank 0's own devices: tiles from the queue, results to the serving thread.
class LocalTiles : public TileSource {
public:
    explicit LocalTiles(WorkQueue& queue) : queue_(queue) {}
    std::optional<TileWork> next() override { return queue_.take(); }
    void done(const TileWork& work, RenderResult&& r) override {
        std::lock_guard lock(mutex_);
        results_.emplace_back(work, std::move(r));
    }
    std::deque<std::pair<TileWork, RenderResult>> take_results() {
        std::lock_guard lock(mutex_);
        return std::exchange(results_, {});
    }

private:
    WorkQueue& queue_;
    std::mutex mutex_;
    std::deque<std::pair<TileWork, RenderResult>> results_;
};

}  // namespace kdrt::cluster
