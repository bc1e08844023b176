// glibc's allocator, tuned for a renderer that exits after its frames.
//
// A tree build allocates and frees big object lists at every level. With
// glibc's defaults, lists above the (adaptive) mmap threshold get fresh pages
// from the kernel each time, and freed memory at the top of the heap is
// handed back and taken again: every page comes back zeroed, one fault at a
// time. Keeping that memory saves most of that system time for a little more
// peak memory; the mmap threshold is what matters. A library must not change its host's allocator, so
// kdrt-render does it; programs built on libkdrt can do the same (mallopt(3),
// or GLIBC_TUNABLES=glibc.malloc.mmap_threshold=33554432).
#pragma once

namespace kdrt::cli {

void tune_allocator();  // no effect where the C library is not glibc

}  // namespace kdrt::cli
