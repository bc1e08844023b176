#include "machine_info.h"

#include "interference.h"

#include <kdrt/device.h>
#include <kdrt/version.h>

#ifdef KDRT_BENCH_HAVE_EMBREE
#include <embree3/rtcore_config.h>
#endif

#include <sys/utsname.h>

#include <array>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <thread>

namespace kdrt::bench {

namespace {

std::string trim(std::string s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    const auto e = s.find_last_not_of(" \t\r\n");
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::string proc_value(const char* file, const std::string& key) {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind(key, 0) != 0) continue;
        const auto colon = line.find(':');
        if (colon != std::string::npos) return trim(line.substr(colon + 1));
    }
    return {};
}

// The commit the source tree is at, when it is a git checkout (best effort).
std::string git_commit() {
#ifdef KDRT_BENCH_SOURCE_DIR
    const std::string cmd = std::string("git -C '") + KDRT_BENCH_SOURCE_DIR + "' rev-parse --short HEAD 2>/dev/null";
    if (FILE* p = popen(cmd.c_str(), "r")) {
        std::array<char, 64> buf{};
        std::string out;
        while (std::fgets(buf.data(), static_cast<int>(buf.size()), p)) out += buf.data();
        pclose(p);
        return trim(out);
    }
#endif
    return {};
}

std::string now_iso8601() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    localtime_r(&t, &tm);
    char buf[64];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S%z", &tm);
    return buf;
}

// Started with the first machine_info() call: the whole command's interference.
Interference& command_interference() {
    static Interference i;
    return i;
}

MachineInfo collect() {
    command_interference().restart();
    MachineInfo m;
    m.date = now_iso8601();
    m.load_at_start = load_average();
    m.cpu_model = proc_value("/proc/cpuinfo", "model name");
    if (m.cpu_model.empty()) m.cpu_model = "unknown CPU";
    m.logical_cpus = std::thread::hardware_concurrency();
    const std::string mem = proc_value("/proc/meminfo", "MemTotal");  // "24576000 kB"
    if (!mem.empty()) m.memory_gib = std::stod(mem) / (1024.0 * 1024.0);
    utsname u{};
    if (uname(&u) == 0) m.os = std::string(u.sysname) + " " + u.release + " " + u.machine;
    try {
        for (const DeviceInfo& d : list_devices()) {
            if (d.id == "cpu") continue;
            m.opencl.push_back(d.id + ": " + d.platform + " | " + d.name + " | " + d.type + " | driver " +
                               d.driver_version + " | " + std::to_string(d.compute_units) + " compute units");
        }
    } catch (const std::exception& e) {
        m.opencl.push_back(std::string("OpenCL unavailable: ") + e.what());
    }
    if (m.opencl.empty()) m.opencl.push_back("no OpenCL device");
    std::ostringstream sw;
    sw << "kdrt " << KDRT_VERSION_STRING;
    const std::string commit = git_commit();
    if (!commit.empty()) sw << " (commit " << commit << ")";
#if defined(__clang__)
    sw << ", clang " << __clang_major__ << "." << __clang_minor__;
#elif defined(__GNUC__)
    sw << ", gcc " << __GNUC__ << "." << __GNUC_MINOR__;
#endif
#ifdef NDEBUG
    sw << " -O (release)";
#else
    sw << " (debug build: figures are not representative)";
#endif
#ifdef KDRT_BENCH_HAVE_EMBREE
    sw << ", Embree " << RTC_VERSION_STRING;
#else
    sw << ", built without Embree";
#endif
    m.software = sw.str();
    return m;
}

}  // namespace

const MachineInfo& machine_info() {
    static const MachineInfo info = collect();
    return info;
}

std::string load_average() {
    std::ifstream in("/proc/loadavg");
    std::string a, b, c;
    if (!(in >> a >> b >> c)) return "unknown";
    return a + " " + b + " " + c;
}

std::vector<std::string> machine_lines() {
    const MachineInfo& m = machine_info();
    char mem[32];
    std::snprintf(mem, sizeof mem, "%.1f", m.memory_gib);
    std::vector<std::string> lines{
        "date: " + m.date,
        "machine: " + m.cpu_model + ", " + std::to_string(m.logical_cpus) + " logical CPUs, " + mem + " GiB RAM, " +
            m.os,
        "load average (1/5/15 min): " + m.load_at_start + " at start, " + load_average() + " at the end; other "
            "processes kept " + [] {
                char b[32];
                std::snprintf(b, sizeof b, "%.2f", command_interference().other_cores());
                return std::string(b);
            }() + " cores busy on average during the run",
    };
    for (const std::string& cl : m.opencl) lines.push_back("OpenCL " + cl);
    lines.push_back("software: " + m.software);
    return lines;
}

}  // namespace kdrt::bench
