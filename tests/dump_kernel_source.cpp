// kdrt_dump_kernel_source <out.cl>: writes the assembled OpenCL program source
// (kdrt_shared.h + cl/*.cl with #line markers) for offline compilers; used by
// the spir_strict_compile test (cmake/KdrtSpirCheck.cmake).
#include "opencl/embedded_cl.h"

#include <cstdio>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s <output.cl>\n", argc > 0 ? argv[0] : "kdrt_dump_kernel_source");
        return 2;
    }
    const std::string source = kdrt::detail::ocl::assemble_kernel_source();
    std::ofstream out(argv[1], std::ios::binary | std::ios::trunc);
    out.write(source.data(), static_cast<std::streamsize>(source.size()));
    out.close();
    if (!out) {
        std::fprintf(stderr, "kdrt_dump_kernel_source: cannot write %s\n", argv[1]);
        return 1;
    }
    return 0;
}
