// Loops over big arrays cut into chunks of a fixed size, run in parallel.
//
// Fixed chunks, not TBB's adaptive ranges: a caller can keep one result per
// chunk and combine them in chunk order, which gives the same answer as a
// serial loop for any number of threads. Arrays of one chunk run on the
// calling thread, without the scheduler.
#pragma once

#include "common/tsan_fork_join.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace kdrt::detail {

// Elements per chunk: big enough that a chunk costs far more than a task,
// small enough that two threads share a few million elements evenly.
inline constexpr std::size_t kParallelChunk = 16384;

inline std::size_t chunk_count(std::size_t n, std::size_t chunk = kParallelChunk) { return (n + chunk - 1) / chunk; }

// f(chunk index, begin, end) for every chunk of [0, n).
template <class F>
void for_each_chunk(std::size_t n, F&& f, std::size_t chunk = kParallelChunk) {
    const std::size_t chunks = chunk_count(n, chunk);
    auto run = [&](std::size_t c) { f(c, c * chunk, std::min(n, (c + 1) * chunk)); };
    if (chunks <= 1) {
        if (chunks == 1) run(0);
        return;
    }
    auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c < r.end(); ++c) run(c);
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), tsan.task(body));
}

// The smallest i in [0, n) with bad(i), or n when there is none: what a serial
// scan finds, so a caller reports the same first fault either way.
template <class Bad>
std::size_t first_index_where(std::size_t n, Bad&& bad) {
    std::vector<std::size_t> first(chunk_count(n), n);
    for_each_chunk(n, [&](std::size_t c, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            if (bad(i)) {
                first[c] = i;
                return;
            }
    });
    for (std::size_t i : first)
        if (i < n) return i;
    return n;
}

}  // namespace kdrt::detail
