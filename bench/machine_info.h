// What every output of kdrt-bench carries: the machine, the OpenCL platforms
// and drivers, the software versions, the date and the load at the time.
#pragma once

#include <string>
#include <vector>

namespace kdrt::bench {

struct MachineInfo {
    std::string date;               // ISO 8601, local time with offset
    std::string cpu_model;          // /proc/cpuinfo "model name"
    unsigned logical_cpus = 0;      // what the cpu device and Embree threads use
    double memory_gib = 0.0;        // MemTotal
    std::string os;                 // uname: system, release, machine
    std::vector<std::string> opencl;  // one line per OpenCL device: id, platform, device, driver
    std::string software;           // kdrt version and commit, compiler, Embree
    std::string load_at_start;      // /proc/loadavg when machine_info() was first called
};

// Collected once per process, on the first call: call it when a command starts
// (OpenCL is initialised here: set POCL_CACHE_DIR before).
const MachineInfo& machine_info();

// The 1, 5 and 15 minute load averages from /proc/loadavg, read now.
std::string load_average();

// Lines "key: value" describing the machine, for Markdown lists and CSV comments.
std::vector<std::string> machine_lines();

}  // namespace kdrt::bench
