// OpenCL event profiling of one frame (OpenClExecution::profile_commands): each
// enqueue asks for an event under a name, and the frame's end sums their
// device times per name and bounce level. When profiling is off, event()
// returns nullptr and the enqueues are exactly the unprofiled ones.
#pragma once

#include "opencl/cl.h"

#include <kdrt/render_stats.h>

#include <string>
#include <vector>

namespace kdrt::detail::ocl {

class CommandProfile {
public:
    explicit CommandProfile(bool on) : on_(on) {}

    bool on() const { return on_; }

    // Where the next command's event goes (nullptr when off).
    cl::Event* event(const char* command, int level = 0);

    // Per command and level, in the order first seen, and the union of their
    // [start, end] intervals in ms. Every recorded command must have completed.
    std::vector<CommandTime> totals(double* busy_ms) const;

private:
    struct Recorded {
        const char* command;
        int level;
        cl::Event event;
    };
    bool on_;
    std::vector<Recorded> recorded_;
};

}  // namespace kdrt::detail::ocl
