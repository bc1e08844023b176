#include "progress_bar.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unistd.h>

namespace kdrt::cli {

namespace {

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

// "12.3s", "4m05s", "2h03m"; "?" when unknown.
void format_duration(char* out, std::size_t size, double s) {
    if (!(s >= 0.0)) std::snprintf(out, size, "?");
    else if (s < 60.0) std::snprintf(out, size, "%.1fs", s);
    else if (s < 3600.0) std::snprintf(out, size, "%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
    else std::snprintf(out, size, "%dh%02dm", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
}

}  // namespace

double remaining_seconds(double fraction, double elapsed) {
    if (!(fraction >= 0.01) || !(elapsed > 0.0)) return -1.0;
    return fraction >= 1.0 ? 0.0 : elapsed * (1.0 - fraction) / fraction;
}

ProgressBar::ProgressBar(ProgressMode mode)
    : enabled_(mode == ProgressMode::Always || (mode == ProgressMode::Auto && isatty(STDERR_FILENO))),
      terminal_(isatty(STDERR_FILENO)), immediate_(mode == ProgressMode::Always), start_(Clock::now()),
      phase_start_(start_), last_line_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction) {
    if (!enabled_ || !(fraction >= 0.0)) return;
    const Clock::time_point now = Clock::now();
    if (fraction < last_fraction_) phase_start_ = now;  // the next phase (build, upload, render) began
    last_fraction_ = fraction;
    const double elapsed = seconds(now - start_);
    if (!shown_ && !immediate_ && elapsed < 1.0) return;
    const int percent = static_cast<int>(std::floor(std::min(fraction, 1.0) * 100.0));
    // A terminal gets every percent; a file or pipe a line per 10 % or per 5 s.
    const bool due = terminal_ ? percent != last_percent_
                               : !shown_ || percent / 10 != last_percent_ / 10 || seconds(now - last_line_) >= 5.0;
    if (shown_ && !due) return;
    last_percent_ = percent;
    last_line_ = now;
    show(fraction, elapsed, remaining_seconds(fraction, seconds(now - phase_start_)));
}

void ProgressBar::show(double fraction, double elapsed, double eta) {
    shown_ = true;
    char took[32], left[32];
    format_duration(took, sizeof took, elapsed);
    format_duration(left, sizeof left, eta);
    const int percent = last_percent_;
    if (terminal_) {
        const int width = 40, filled = static_cast<int>(std::min(fraction, 1.0) * width);
        std::fprintf(stderr, "\r[%.*s%*s] %3d%%  %s  ETA %s\x1b[K", filled, "########################################",
                     width - filled, "", percent, took, left);
    } else {
        std::fprintf(stderr, "kdrt-render: progress %3d%%  %s  ETA %s\n", percent, took, left);
    }
    std::fflush(stderr);
}

void ProgressBar::finish() {
    if (shown_ && terminal_) std::fputc('\n', stderr);
    shown_ = false;
    enabled_ = false;
}

}  // namespace kdrt::cli
