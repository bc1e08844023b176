#include "progress_bar.h"

#include <cstdio>
#include <unistd.h>

namespace kdrt::cli {

ProgressBar::ProgressBar(bool enabled)
    : enabled_(enabled && isatty(STDERR_FILENO)), start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction) {
    if (!enabled_) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (!shown_ && elapsed < 1.0) return;
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    if (shown_ && percent == last_percent_) return;
    shown_ = true;
    last_percent_ = percent;
    const int width = 40, filled = percent * width / 100;
    std::fprintf(stderr, "\r[%.*s%*s] %3d%%  %.1fs", filled, "########################################",
                 width - filled, "", percent, elapsed);
    std::fflush(stderr);
}

void ProgressBar::finish() {
    if (shown_) {
        std::fputc('\n', stderr);
        shown_ = false;
    }
}

}  // namespace kdrt::cli
