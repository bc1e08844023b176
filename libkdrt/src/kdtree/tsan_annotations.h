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

#ifdef KDRT_TSAN
inline char tsan_fork_sync = 0, tsan_join_sync = 0;
inline void tsan_fork() { __tsan_release(&tsan_fork_sync); }
inline void tsan_join() { __tsan_acquire(&tsan_join_sync); }
#else
inline void tsan_fork() {}
inline void tsan_join() {}
#endif

// Opens each task body, before it reads anything its spawner wrote (global
// sync addresses: a task reaches them without reading its closure). The
// task closures must not be const objects, or the compiler may read their
// captures before this acquire.
// tsan_fork() before a parallel call, tsan_join() after it.
struct TsanTask {
#ifdef KDRT_TSAN
    TsanTask() { __tsan_acquire(&tsan_fork_sync); }
    ~TsanTask() { __tsan_release(&tsan_join_sync); }
#endif
};

// Calls tsan_join() when it goes out of scope, also when the parallel call
// throws (a cancelled build): declared after the data the tasks wrote, so the
// join comes before that data is destroyed.
struct TsanJoinOnExit {
    TsanJoinOnExit() = default;
    TsanJoinOnExit(const TsanJoinOnExit&) = delete;
    TsanJoinOnExit& operator=(const TsanJoinOnExit&) = delete;
    ~TsanJoinOnExit() { tsan_join(); }
};

}  // namespace kdrt::detail
