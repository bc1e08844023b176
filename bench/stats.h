// Timing helpers: a stopwatch and the median that every figure in
// BENCHMARKS.md reports (warm-up runs are dropped by the callers).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace kdrt::bench {

// A figure not measured (skipped, failed, not applicable); tables print "-".
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class Stopwatch {
public:
    Stopwatch() : start_(std::chrono::steady_clock::now()) {}
    void restart() { start_ = std::chrono::steady_clock::now(); }
    double ms() const {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    std::chrono::steady_clock::time_point start_;
};

// Median of the values (mean of the middle two for an even count); NaN when empty.
inline double median(std::vector<double> v) {
    if (v.empty()) return kNaN;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Millions of rays per second from a ray count and milliseconds.
inline double mrays_per_s(double rays, double ms) { return ms > 0.0 ? rays / (ms * 1000.0) : 0.0; }

}  // namespace kdrt::bench
