// The bench's own worker pool for the Embree renderer and the camera-ray
// throughput test: the same scheme as the cpu device (one std::thread per
// worker, work handed out in chunks from an atomic counter), so thread
// counts mean the same on both sides.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace kdrt::bench {

// The cpu device's rule: 0 means every logical CPU.
inline int worker_count(int threads) {
    const int n = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());
    return std::clamp(n, 1, 256);
}

// Calls body(begin, end, worker) for chunks of [0, n) on `threads` workers
// (the calling thread is worker 0).
template <class Body>
void parallel_chunks(std::size_t n, int threads, std::size_t chunk, Body&& body) {
    std::atomic<std::size_t> next{0};
    auto work = [&](int worker) {
        for (std::size_t b = next.fetch_add(chunk); b < n; b = next.fetch_add(chunk))
            body(b, std::min(n, b + chunk), worker);
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(work, i);
    work(0);
    for (std::thread& t : pool) t.join();
}

}  // namespace kdrt::bench
