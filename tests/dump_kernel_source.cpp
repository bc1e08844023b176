// kdrt_dump_kernel_source <out.cl> [<variants.txt>]: writes the assembled
// OpenCL program source (the shared headers + cl/*.cl with #line markers) for
// offline compilers, and optionally every option set the kernel
// specialisation can produce, one per line. Used by the spir_strict_compile
// test (cmake/KdrtSpirCheck.cmake).
#include "opencl/embedded_cl.h"
#include "opencl/kernel_variant.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <string>

namespace {

// Traversal t of the six the kernels have: the kd-tree's five (Traversal),
// then the BVH's stack traversal.
constexpr int kTraversals = 6;
void set_traversal(kdrt::detail::KernelVariant& v, int t) {
    v.accel = t == 5 ? kdrt::Accel::Bvh : kdrt::Accel::KdTree;
    v.traversal = t == 5 ? kdrt::Traversal::Stack : static_cast<kdrt::Traversal>(t);
}

// Every feature set kernel_options() can be called with: geometry (none,
// spheres, triangles with or without shading normals, both), lights on/off,
// the bounce variants (none; mirrors; glass; both), each traversal (the BVH's too), fp64 on/off,
// in float and (with fp64) double; every accuracy knob on the generic set;
// and the code for CPU devices.
std::set<std::string> all_variants() {
    std::set<std::string> out;
    using kdrt::detail::KernelVariant;
    for (int geometry = 0; geometry < 6; ++geometry)
        for (int lights = 0; lights < 2; ++lights)
            for (int bounce = 0; bounce < 4; ++bounce)
                for (int traversal = 0; traversal < kTraversals; ++traversal)
                    for (int precision = 0; precision < 3; ++precision) {
                        KernelVariant v;
                        kdrt::SceneFeatures& f = v.features;
                        f.spheres = geometry == 1 || geometry >= 4;
                        f.triangles = geometry == 2 || geometry == 3 || geometry >= 4;
                        v.normals = geometry == 3 || geometry == 5;
                        f.lights = lights == 1;
                        f.reflection = bounce & 1;
                        f.refraction = bounce & 2;
                        f.max_depth = bounce ? 15 : 1;
                        set_traversal(v, traversal);
                        v.fp64 = precision > 0;  // 0: float without fp64, 1: float with, 2: double
                        v.precision = precision == 2 ? kdrt::Precision::Double : kdrt::Precision::Float;
                        out.insert(kdrt::detail::kernel_options(v));
                    }
    // A CPU device's code (the leaf test four triangles at a time, packets
    // with the stack traversal, prefetches): with triangles (with and without
    // spheres), every traversal and precision, with and without the mailbox,
    // with bounces and lights (and packed leaves) or neither; and every
    // accuracy knob below.
    for (int spheres = 0; spheres < 2; ++spheres)
        for (int traversal = 0; traversal < kTraversals; ++traversal)
            for (int precision = 0; precision < 3; ++precision)
                for (int plain = 0; plain < 2; ++plain) {
                    KernelVariant v;
                    v.features = kdrt::SceneFeatures::all(plain ? 1 : 15);
                    v.features.spheres = spheres == 1;
                    v.features.lights = plain == 0;
                    set_traversal(v, traversal);
                    v.fp64 = precision > 0;
                    v.precision = precision == 2 ? kdrt::Precision::Double : kdrt::Precision::Float;
                    v.cpu_device = true;
                    v.mailbox = plain == 0 && v.accel == kdrt::Accel::KdTree;  // a BVH never has one
                    v.packed_leaves = plain == 0;
                    out.insert(kdrt::detail::kernel_options(v));
                }
    for (int traversal = 0; traversal < kTraversals; ++traversal)
        for (int knobs = 0; knobs < 8; ++knobs)
            for (int precision = 0; precision < 2; ++precision) {
                KernelVariant v;
                v.features = kdrt::SceneFeatures::all(15);
                set_traversal(v, traversal);
                v.fp64 = true;
                v.precision = precision ? kdrt::Precision::Double : kdrt::Precision::Float;
                v.triangle_test = (knobs & 1) ? kdrt::TriangleTest::MollerTrumbore : kdrt::TriangleTest::Watertight;
                v.sphere_test = (knobs & 2) ? kdrt::SphereTest::Textbook : kdrt::SphereTest::Careful;
                v.self_intersection =
                    (knobs & 4) ? kdrt::SelfIntersection::FixedEpsilon : kdrt::SelfIntersection::ScaleAware;
                out.insert(kdrt::detail::kernel_options(v));
                if (v.traversal == kdrt::Traversal::Stack || v.traversal == kdrt::Traversal::Ropes) {
                    v.cpu_device = true;  // with packets (stack) and without (ropes, the BVH)
                    v.mailbox = v.accel == kdrt::Accel::KdTree;
                    out.insert(kdrt::detail::kernel_options(v));
                }
            }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2 && argc != 3) {
        std::fprintf(stderr, "usage: %s <output.cl> [<variants.txt>]\n", argc > 0 ? argv[0] : "kdrt_dump_kernel_source");
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
    if (argc == 3) {
        std::ofstream variants(argv[2], std::ios::trunc);
        for (const std::string& v : all_variants()) variants << v << "\n";
        if (!variants) {
            std::fprintf(stderr, "kdrt_dump_kernel_source: cannot write %s\n", argv[2]);
            return 1;
        }
    }
    return 0;
}
