// Happens-before edges for ThreadSanitizer where oneTBB's scheduler orders
// memory. Debian's libtbb is not instrumented, so TSan cannot see that what a
// parallel call's spawner wrote precedes its tasks, nor that the tasks precede
// the call's return. TsanForkJoin states those two edges (the guarantees TBB
// documents) for one parallel call, on addresses of its own: a race between
// two tasks that may run at once, or with another call, stays visible.
//
// Why a wrapper and not an annotation inside each task body: the body's first
// loads of its closure (on the spawner's stack) may be scheduled before any
// call in the body, so an acquire written in the body can come too late (TSan
// then reports the spawner's write of the closure against the worker's read).
// The wrapper acquires before it reads anything and calls the body, which is
// not inlined into it (sanitizer attributes differ); the wrapper's own read of
// the body's address is not instrumented. No code outside TSan builds.
#pragma once

#include <utility>

#if defined(__SANITIZE_THREAD__)
#define KDRT_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define KDRT_TSAN 1
#endif
#endif

#ifdef KDRT_TSAN
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#endif

namespace kdrt::detail {

#ifdef KDRT_TSAN

// Declare it just before the parallel call, in a block that ends just after
// it, after everything the tasks read or write: the fork edge is taken at
// construction, the join edge at destruction (also when the call throws, as a
// cancelled build does), before that data is destroyed.
class TsanForkJoin {
public:
    TsanForkJoin() { __tsan_release(&fork_); }
    ~TsanForkJoin() { __tsan_acquire(&join_); }
    TsanForkJoin(const TsanForkJoin&) = delete;
    TsanForkJoin& operator=(const TsanForkJoin&) = delete;

    template <class F>
    class Task {
    public:
        Task(F& f, TsanForkJoin& s) : f_(&f), s_(&s) {}
        template <class... A>
        __attribute__((no_sanitize("thread"))) void operator()(A&&... a) const {
            __tsan_acquire(&s_->fork_);
            const Done done{s_};
            (*f_)(std::forward<A>(a)...);
        }

    private:
        struct Done {
            TsanForkJoin* s;
            __attribute__((no_sanitize("thread"))) ~Done() { __tsan_release(&s->join_); }
        };
        F* f_;
        TsanForkJoin* s_;
    };

    // The body to hand to the TBB call in place of f (which must outlive it).
    template <class F>
    Task<F> task(F& f) {
        return Task<F>(f, *this);
    }

private:
    char fork_ = 0, join_ = 0;
};

#else

class TsanForkJoin {
public:
    TsanForkJoin() = default;
    TsanForkJoin(const TsanForkJoin&) = delete;
    TsanForkJoin& operator=(const TsanForkJoin&) = delete;
    template <class F>
    F& task(F& f) {
        return f;
    }
};

#endif

}  // namespace kdrt::detail
