// KDRT_ASSERT(condition): an invariant the code relies on (a stack bound, an
// index inside its array), checked in builds without NDEBUG (the sanitizer
// presets) and compiled out of release builds. Inputs are never checked this
// way: bad input gets an Error naming it.
#pragma once

#ifdef NDEBUG
#define KDRT_ASSERT(condition) static_cast<void>(0)
#else
#include <cstdio>
#include <cstdlib>
#define KDRT_ASSERT(condition)                                                                                 \
    ((condition) ? static_cast<void>(0)                                                                       \
                 : (std::fprintf(stderr, "%s:%d: kdrt invariant failed: %s\n", __FILE__, __LINE__, #condition), \
                    std::abort()))
#endif
