// KDRT_API marks what libkdrt.so exports. The library is compiled with hidden
// visibility and linked with a version script (libkdrt/kdrt.map), so a
// public declaration without KDRT_API does not link for users of the shared
// library: put it on every class with out-of-line members (or a vtable) and
// every free function declared in these headers.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define KDRT_API __attribute__((visibility("default")))
#else
#define KDRT_API
#endif
