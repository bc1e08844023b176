#include "cpu/run_with_progress.h"

#include <kdrt/error.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace kdrt::detail {

void run_with_progress(const std::function<void()>& work, std::atomic<bool>& cancel,
                       const std::function<double()>& fraction_done, const std::function<bool(double)>& progress) {
    constexpr auto kPollInterval = std::chrono::milliseconds(50);
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    std::exception_ptr work_error;
    std::thread worker([&] {
        try {
            work();
        } catch (...) {
            work_error = std::current_exception();
        }
        std::lock_guard lock(mutex);
        done = true;
        finished.notify_one();
    });

    std::exception_ptr callback_error;
    bool stop = false;
    for (;;) {
        {
            std::unique_lock lock(mutex);
            if (finished.wait_for(lock, kPollInterval, [&] { return done; })) break;
        }
        if (stop) continue;  // cancelled: waiting for the work to return
        try {
            stop = !progress(fraction_done());
        } catch (...) {
            callback_error = std::current_exception();
            stop = true;
        }
        if (stop) cancel.store(true, std::memory_order_relaxed);
    }
    worker.join();
    if (callback_error) std::rethrow_exception(callback_error);
    if (work_error) std::rethrow_exception(work_error);
    if (stop) throw Error(ErrorCode::Cancelled, "render cancelled");
    if (!progress(1.0)) throw Error(ErrorCode::Cancelled, "render cancelled");
}

}  // namespace kdrt::detail
