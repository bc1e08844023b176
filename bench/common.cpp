#include "common.h"

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/scene_loader.h>
#include <kdrt/version.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <random>

namespace kdrt::bench {

namespace {

std::string utc_now() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

}  // namespace

double median(std::vector<double> v) {
    if (v.empty()) return kNaN;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

const std::vector<std::string>& study_scene_names() {
    static const std::vector<std::string> names{"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"};
    return names;
}

std::vector<NamedScene> load_scenes(const std::vector<std::string>& names, const std::filesystem::path& dir) {
    std::filesystem::path base = dir;
    if (base.empty()) {
        const char* env = std::getenv("KDRT_SCENES_DIR");
        base = env && *env ? env : KDRT_BENCH_SCENES_DIR;
    }
    std::vector<NamedScene> out;
    for (const std::string& n : names) {
        std::filesystem::path p = n;
        if (!std::filesystem::is_regular_file(p)) p = base / (n + ".json");
        if (!std::filesystem::is_regular_file(p))
            throw Error(ErrorCode::Io, "scene '" + n + "': neither a file nor " + p.string());
        out.push_back({p.stem().string(), load_scene(p)});
    }
    return out;
}

void parse_size(const std::string& text, int& width, int& height) {
    const auto x = text.find('x');
    try {
        if (x == std::string::npos) throw std::invalid_argument("no x");
        std::size_t a = 0, b = 0;
        width = std::stoi(text.substr(0, x), &a);
        height = std::stoi(text.substr(x + 1), &b);
        if (a != x || b != text.size() - x - 1 || width < 1 || height < 1 || width > 16384 || height > 16384)
            throw std::invalid_argument("range");
    } catch (const std::exception&) {
        throw Error(ErrorCode::InvalidArgument, "--size '" + text + "': expected WxH, e.g. 500x500");
    }
}

std::vector<std::string> all_device_ids() {
    std::vector<std::string> ids;
    for (const DeviceInfo& d : list_devices()) ids.push_back(d.id);
    return ids;
}

Json result_header(int argc, char** argv) {
    std::string command = "kdrt-bench";
    for (int i = 1; i < argc; ++i) command.append(" ").append(argv[i]);
    Json devices = Json::array();
    for (const DeviceInfo& d : list_devices())
        devices.push_back({{"id", d.id}, {"name", d.name}, {"platform", d.platform}, {"type", d.type},
                           {"driver", d.driver_version}, {"compute_units", d.compute_units}});
    return {{"command", command}, {"kdrt_version", KDRT_VERSION_STRING}, {"started", utc_now()},
            {"threads", worker_count(0)}, {"devices", devices}};
}

void write_result(const std::filesystem::path& out, const std::string& name, Json result) {
    result["finished"] = utc_now();
    std::filesystem::create_directories(out);
    const std::filesystem::path path = out / (name + ".json");
    std::ofstream file(path);
    file << result.dump(1) << "\n";
    if (!file) throw Error(ErrorCode::Io, path.string() + ": cannot write");
    std::fprintf(stderr, "kdrt-bench: wrote %s\n", path.c_str());
}

TempDir::TempDir(const std::string& prefix) {
    std::random_device seed;
    for (int attempt = 0; attempt < 16; ++attempt) {
        path_ = std::filesystem::temp_directory_path() / (prefix + "-" + std::to_string(seed()));
        if (std::filesystem::create_directory(path_)) return;
    }
    throw Error(ErrorCode::Io, "cannot make a temporary directory " + path_.string());
}

TempDir::~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
}

}  // namespace kdrt::bench
