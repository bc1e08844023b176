#include "interrupt.h"

#include "common/atomic_file.h"

#include <kdrt/error.h>

#include <atomic>
#include <csignal>

namespace kdrt::cli {

namespace {

std::atomic<int> first_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch a lock-free atomic");

extern "C" void on_stop_signal(int signal) {
    int none = 0;
    if (first_signal.compare_exchange_strong(none, signal, std::memory_order_relaxed)) return;
    // The second signal: no more waiting for the run to wind down.
    kdrt::detail::remove_live_temporaries();
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

void handle(int signal) {
    struct sigaction previous {};
    if (sigaction(signal, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) return;
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(signal, &action, nullptr);
}

}  // namespace

void install_interrupt_handler() {
    for (int signal : {SIGINT, SIGTERM, SIGHUP}) handle(signal);
    std::signal(SIGXFSZ, SIG_IGN);
}

bool interrupted() { return first_signal.load(std::memory_order_relaxed) != 0; }

int interrupt_signal() { return first_signal.load(std::memory_order_relaxed); }

void stop_if_interrupted() {
    if (interrupted()) throw Error(ErrorCode::Cancelled, "interrupted");
}

}  // namespace kdrt::cli
