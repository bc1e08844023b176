#include "interrupt.h"

#include <atomic>
#include <csignal>

namespace kdrt::cli {

namespace {

std::atomic<bool> flag{false};
static_assert(std::atomic<bool>::is_always_lock_free, "a signal handler may only touch a lock-free atomic");

extern "C" void on_interrupt(int) { flag.store(true, std::memory_order_relaxed); }

}  // namespace

void install_interrupt_handler() {
    // A SIGINT ignored on entry (a background job of a shell without job
    // control, nohup) stays ignored, as the convention is.
    struct sigaction previous {};
    if (sigaction(SIGINT, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) return;
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND | SA_RESTART;  // the second SIGINT gets the default action
    sigaction(SIGINT, &action, nullptr);
}

bool interrupted() { return flag.load(std::memory_order_relaxed); }

}  // namespace kdrt::cli
