#include "opencl/command_profile.h"

#include <algorithm>
#include <utility>

namespace kdrt::detail::ocl {

cl::Event* CommandProfile::event(const char* command, int level) {
    if (!on_) return nullptr;
    recorded_.push_back(Recorded{command, level, cl::Event()});
    return &recorded_.back().event;
}

std::vector<CommandTime> CommandProfile::totals(double* busy_ms) const {
    std::vector<CommandTime> out;
    std::vector<std::pair<cl_ulong, cl_ulong>> spans;  // ns, device clock
    for (const Recorded& r : recorded_) {
        const cl_ulong start = r.event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
        const cl_ulong end = std::max(start, r.event.getProfilingInfo<CL_PROFILING_COMMAND_END>());
        spans.emplace_back(start, end);
        auto it = std::find_if(out.begin(), out.end(), [&](const CommandTime& c) {
            return c.level == r.level && c.command == r.command;
        });
        if (it == out.end()) it = out.insert(out.end(), CommandTime{r.command, r.level, 0, 0.0});
        ++it->count;
        it->device_ms += static_cast<double>(end - start) * 1e-6;
    }
    // The union of the intervals: an in-order queue runs one command at a
    // time, but an implementation may report overlapping transfers.
    std::sort(spans.begin(), spans.end());
    cl_ulong busy = 0, reach = 0;
    for (const auto& [start, end] : spans) {
        const cl_ulong from = std::max(start, reach);
        if (end > from) busy += end - from;
        reach = std::max(reach, end);
    }
    if (busy_ms) *busy_ms = static_cast<double>(busy) * 1e-6;
    return out;
}

}  // namespace kdrt::detail::ocl
