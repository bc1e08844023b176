#include "allocator_tuning.h"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace kdrt::cli {

void tune_allocator() {
#if defined(__GLIBC__)
    // The largest mmap threshold glibc accepts on 64-bit systems (32 MiB), and
    // a trim threshold well above a big mesh's working set.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace kdrt::cli
