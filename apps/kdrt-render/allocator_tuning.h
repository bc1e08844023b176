// glibc's allocator, tuned for a renderer that exits after its frames.
//
// A tree build allocates and frees big object lists at every level. With
// glibc's defaults, lists above the (adaptive) mmap threshold get fresh pages
// from the kernel each time, and freed memory at the top of the heap is
// handed back and taken again: every page comes back zeroed, one fault at a
// time. Keeping that memory took 0.2 s of system time and 7 % of the wall
// time off a 2M-triangle heightfield's whole process, for 66 MiB more peak
// memory (BENCHMARKS.md, 15). A library must not change its host's allocator,
// so kdrt-render does it; programs built on libkdrt can do the same
// (mallopt(3), or GLIBC_TUNABLES=glibc.malloc.trim_threshold=...).
#pragma once

namespace kdrt::cli {

void tune_allocator();  // no effect where the C library is not glibc

}  // namespace kdrt::cli
