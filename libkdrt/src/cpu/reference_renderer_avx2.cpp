// The reference renderer's AVX2 copy (cpu_isa.h). Every header from outside
// cpu/ is included first, under the baseline target, so that no inline
// function the rest of libkdrt shares is compiled for AVX2 here (the linker
// could pick that copy for a processor without it); only what
// render_frame.h brings after the pragma, in the isa_avx2 namespace, is.
// tests/check_cpu_isa_object.cmake checks the object for it.
#define KDRT_CPU_ISA isa_avx2
#define KDRT_CPU_VECTOR_BYTES 32

#include "cpu/reference_renderer.h"

#include "cpu/cpu_isa.h"

#if KDRT_CPU_HAS_AVX2_COPY

#include "common/tsan_fork_join.h"
#include "cpu/run_with_progress.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/render_options.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <emmintrin.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

// x86-64-v3's instructions without its arch=, which would stop GCC inlining
// the baseline helpers above into this code.
#pragma GCC push_options
#pragma GCC target("avx,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c,movbe")
#include "cpu/render_frame.h"
#pragma GCC pop_options

namespace kdrt::detail {

RenderResult render_reference_avx2(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options) {
    return isa_avx2::render_frame_in(scene, tree, options, CpuIsa::Avx2);
}

}  // namespace kdrt::detail

#endif  // KDRT_CPU_HAS_AVX2_COPY
