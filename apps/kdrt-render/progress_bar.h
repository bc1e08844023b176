// Progress on stderr with an estimate of the time left. By default only on a
// terminal and only once a render has taken more than about a second (short
// renders stay silent); --progress forces it (lines of text when stderr is
// not a terminal), --no-progress suppresses it.
#pragma once

#include <chrono>

namespace kdrt::cli {

enum class ProgressMode { Auto, Always, Never };

class ProgressBar {
public:
    explicit ProgressBar(ProgressMode mode);
    ~ProgressBar();
    // The finished fraction of the phase at hand (tree build, upload, render):
    // a fraction lower than the last one starts a new phase and a new estimate.
    void update(double fraction);
    void finish();

private:
    using Clock = std::chrono::steady_clock;
    void show(double fraction, double elapsed, double eta);

    bool enabled_, terminal_, immediate_;
    bool shown_ = false;
    int last_percent_ = -1;
    double last_fraction_ = 0.0;
    Clock::time_point start_, phase_start_, last_line_;
};

// "ETA" for a phase `fraction` done after `elapsed` seconds at a constant rate;
// negative while too little is done to tell.
double remaining_seconds(double fraction, double elapsed);

}  // namespace kdrt::cli
