// The first include of a file that compiles the cpu/ templates as their AVX2
// copy (cpu_isa.h): every header from outside cpu/ that they use, included
// here, before the target pragma, so that its inline functions stay baseline
// code shared with the rest of libkdrt (were one compiled for AVX2 here, the
// linker could keep that copy for every caller, also on a processor without
// AVX). Then KDRT_CPU_AVX2_BEGIN, the cpu/ headers, KDRT_CPU_AVX2_END.
// tests/check_cpu_isa_objects.sh checks the objects for it.
#pragma once

#define KDRT_CPU_ISA isa_avx2
#define KDRT_CPU_VECTOR_BYTES 32

#include "cpu/cpu_isa.h"

#include "bvh/bvh.h"
#include "common/debug_assert.h"
#include "common/ms_since.h"
#include "common/tsan_fork_join.h"
#include "cpu/cpu_tracing.h"
#include "cpu/run_with_progress.h"
#include "device/accel.h"
#include "device/kernel_records.h"
#include "device/query_misses.h"
#include "kdtree/leaf_blocks.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/commit_options.h>
#include <kdrt/frame_options.h>
#include <kdrt/layout.h>
#include <kdrt/render_result.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <emmintrin.h>
#include <immintrin.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

// x86-64-v3's instructions without its arch=, which would stop GCC inlining
// the baseline helpers above into the AVX2 code. Clang's attribute applies to
// the functions declared in between (the templates above keep their code);
// its features are those its processor check can confirm (cpu_isa.cpp).
#ifdef __clang__
#define KDRT_CPU_AVX2_BEGIN                                                                                 \
    _Pragma("clang attribute push(__attribute__((target(\"avx,avx2,fma,bmi,bmi2,popcnt\"))), apply_to = function)")
#define KDRT_CPU_AVX2_END _Pragma("clang attribute pop")
#else
#define KDRT_CPU_AVX2_BEGIN \
    _Pragma("GCC push_options") _Pragma("GCC target(\"avx,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c,movbe\")")
#define KDRT_CPU_AVX2_END _Pragma("GCC pop_options")
#endif
