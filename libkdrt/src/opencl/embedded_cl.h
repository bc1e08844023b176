// The OpenCL C sources compiled into libkdrt (cmake/KdrtEmbedCl.cmake), and
// the single program source assembled from them.
#pragma once

#include <cstddef>
#include <span>
#include <string>

namespace kdrt::detail::ocl {

struct EmbeddedClFile {
    const char* name;  // path relative to the project root, e.g. "cl/intersect.cl"
    const char* text;  // the file's bytes, NUL-terminated
};

// Generated at build time from the headers the kernels share with the host
// and KDRT_CL_FILES (libkdrt/CMakeLists.txt), in that order:
// libkdrt/include/kdrt/layout.h, libkdrt/src/device/kernel_records.h, then cl/*.cl.
extern const EmbeddedClFile kEmbeddedClFiles[];
extern const std::size_t kEmbeddedClFileCount;

// The embedded files concatenated in order, each preceded by
// `#line 1 "<name>"` so build logs name the right file and line. Lines that
// include an embedded header by its file name (`#include "layout.h"`,
// `#include <kdrt/layout.h>`, `"../device/kernel_records.h"`, ...) are
// blanked, keeping the line numbers: the headers come first, so the source
// needs no include path.
std::string assemble_kernel_source();
std::string assemble_kernel_source(std::span<const EmbeddedClFile> files);

}  // namespace kdrt::detail::ocl
