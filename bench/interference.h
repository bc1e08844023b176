// How busy the machine was with other processes while we measured: the CPU
// time all processes used (/proc/stat) minus our own and our children's
// (getrusage), per second of wall time, in cores. On a small machine shared
// with builds and test runs this is what decides whether a figure can stand:
// the table measures a cell again when others took a sizeable share.
#pragma once

#include "stats.h"

#include <chrono>
#include <cstdio>
#include <thread>

namespace kdrt::bench {

class Interference {
public:
    Interference() { restart(); }
    void restart();
    // Average number of cores other processes kept busy since restart() (>= 0; coarse: 10 ms ticks).
    double other_cores() const;
    double elapsed_s() const { return clock_.ms() / 1000.0; }

private:
    double busy_s_ = 0.0, self_s_ = 0.0;
    Stopwatch clock_;
};

// A measurement that shared the machine with more than kBusyCores busy cores
// of other processes is taken again, up to kMaxAttempts times in all,
// kRetryPauseS apart, while the retry budget lasts; below 0.2 s of measuring
// the 10 ms ticks are too coarse to tell.
inline constexpr double kBusyCores = 0.25;
inline constexpr int kMaxAttempts = 3;
inline constexpr int kRetryPauseS = 10;

// Seconds of pauses all retries of this process may still take (--quick: none).
inline double retry_budget_s = 300.0;

inline bool busy(double other_cores, double seconds) { return seconds >= 0.2 && other_cores > kBusyCores; }

// The other processes' share of the machine during a measurement.
struct Quietness {
    double other_cores = 0.0;
    double seconds = 0.0;
    bool too_busy() const { return busy(other_cores, seconds); }
};

// Calls measure() until it ran on a quiet enough machine or the attempts are
// used up; returns how busy the others were during the last attempt.
template <class Measure>
Quietness measure_quietly(Measure&& measure) {
    for (int attempt = 1;; ++attempt) {
        const Interference others;
        measure();
        const Quietness q{others.other_cores(), others.elapsed_s()};
        const double cores = q.other_cores;
        if (!q.too_busy() || attempt >= kMaxAttempts || retry_budget_s < kRetryPauseS) return q;
        retry_budget_s -= kRetryPauseS;
        std::fprintf(stderr, "  (other processes kept %.2f cores busy: measuring again in %d s)\n", cores, kRetryPauseS);
        std::this_thread::sleep_for(std::chrono::seconds(kRetryPauseS));
    }
}

}  // namespace kdrt::bench
