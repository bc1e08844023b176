// The nthreads argument of the Open3D API: the call's work in a oneTBB arena
// of that many threads (kdrt's cpu device and passes run on the caller's arena).
#pragma once

#include <tbb/task_arena.h>

namespace kdrt::python {

template <class F>
void in_arena(int threads, F&& f) {
    if (threads <= 0) return f();
    tbb::task_arena arena(threads);
    arena.execute(f);
}

}  // namespace kdrt::python
