// Happens-before edges for ThreadSanitizer where oneTBB's scheduler orders
// memory. Debian's libtbb is not instrumented, so TSan cannot see that what a
// task's spawner wrote precedes the task, nor that a task precedes the return
// of the parallel call that ran it. The builder states those two edges (the
// guarantees TBB documents) around each parallel call; a race between two
// tasks that may run at once stays visible. No code outside TSan builds.
#pragma once

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

// One fork/join of parallel tasks: fork() before the parallel call, task()
// around each task body, join() after the call.
class TsanForkJoin {
public:
    void fork() { release(&fork_); }
    template <class F>
    auto task(F&& body) {
        acquire(&fork_);
        struct Done {
            TsanForkJoin* self;
            ~Done() { release(&self->join_); }
        } done{this};
        return body();
    }
    void join() { acquire(&join_); }

private:
#ifdef KDRT_TSAN
    static void release(char* p) { __tsan_release(p); }
    static void acquire(char* p) { __tsan_acquire(p); }
#else
    static void release(char*) {}
    static void acquire(char*) {}
#endif
    char fork_ = 0, join_ = 0;
};

}  // namespace kdrt::detail
