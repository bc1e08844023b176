// A progress bar on stderr: only on a terminal, and only once a render has
// taken more than about a second (short renders stay silent).
#pragma once

#include <chrono>

namespace kdrt::cli {

class ProgressBar {
public:
    explicit ProgressBar(bool enabled);
    ~ProgressBar();
    void update(double fraction);
    void finish();

private:
    bool enabled_;
    bool shown_ = false;
    int last_percent_ = -1;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace kdrt::cli
