// Long parallel work that the caller can follow and cancel: the work runs on
// its own thread while the calling thread calls `progress` at least every
// 50 ms (so the callback runs on the calling thread and need not be
// thread-safe). progress returning false sets `cancel`, which the work polls
// and then returns early; the call then throws kdrt::Error(Cancelled). A
// callback that throws cancels the same way and its exception is rethrown;
// an exception of the work is rethrown too. The work is always joined first.
#pragma once

#include <atomic>
#include <functional>

namespace kdrt::detail {

void run_with_progress(const std::function<void()>& work, std::atomic<bool>& cancel,
                       const std::function<double()>& fraction_done, const std::function<bool(double)>& progress);

}  // namespace kdrt::detail
