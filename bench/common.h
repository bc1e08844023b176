// What every kdrt-bench command shares: a stopwatch and the median, the worker
// pool that gives Embree and kdrt the same threads, the scenes, and the JSON
// file each command leaves for bench/write_benchmarks.py.
#pragma once

#include <kdrt/scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>
#include <thread>
#include <vector>

namespace kdrt::bench {

using Json = nlohmann::ordered_json;

// A figure not measured (skipped, failed); it is written as JSON null.
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

// The median (mean of the middle two for an even count); NaN when empty.
double median(std::vector<double> v);

// The median of `runs` builds' milliseconds (build() times one and returns
// them), after one build left out when runs > 1: it touches fresh memory and
// starts thread pools, which the others do not.
template <class Build>
double median_build_ms(int runs, Build&& build) {
    std::vector<double> ms;
    for (int r = runs > 1 ? -1 : 0; r < runs; ++r) {
        const double t = build();
        if (r >= 0) ms.push_back(t);
    }
    return median(ms);
}

// Millions of rays per second.
inline double mrays_per_s(double rays, double ms) { return ms > 0.0 ? rays / (ms * 1000.0) : kNaN; }

// The cpu device's rule: 0 means every logical CPU.
inline int worker_count(int threads) {
    const int n = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());
    return std::clamp(n, 1, 256);
}

// body(begin, end, worker) over chunks of [0, n) on `threads` workers handing
// out chunks from a counter, as the cpu device does (the caller is worker 0).
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

struct NamedScene {
    std::string name;  // the file's stem, or the generated mesh's name
    Scene scene;
};

// The study's scenes in its column order: 2x2x4, insane, purple-wall, lens, ball-o-calypse.
const std::vector<std::string>& study_scene_names();

// Each entry is a file path, or a name looked up as DIR/NAME.json (DIR: `dir`,
// else $KDRT_SCENES_DIR, else the source tree's scenes/).
std::vector<NamedScene> load_scenes(const std::vector<std::string>& names, const std::filesystem::path& dir);

// "500x500" -> 500, 500; throws kdrt::Error(InvalidArgument).
void parse_size(const std::string& text, int& width, int& height);

// The device ids list_devices() reports: cpu, then each OpenCL device.
std::vector<std::string> all_device_ids();

// A command's result: {"command", "kdrt_version", "started", "devices", ...}
// and the caller's fields. write_result() adds "finished" and writes
// OUT/NAME.json, saying so on stderr.
Json result_header(int argc, char** argv);
void write_result(const std::filesystem::path& out, const std::string& name, Json result);

// A directory of its own under the system's temporary directory, removed
// with everything in it when the object goes.
class TempDir {
public:
    explicit TempDir(const std::string& prefix);
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

}  // namespace kdrt::bench
