#include "cpu/cpu_isa.h"

#include <cstdlib>
#include <cstring>

namespace kdrt::detail {

namespace {

bool processor_runs_avx2_copy() {
#if KDRT_CPU_HAS_AVX2_COPY
    // The runtime's check includes the operating system's saving of the AVX
    // registers. Clang 15 knows no "x86-64-v3": the features its copy uses.
    static const bool runs = [] {
        __builtin_cpu_init();
#ifdef __clang__
        return __builtin_cpu_supports("avx") && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("popcnt");
#else
        return __builtin_cpu_supports("x86-64-v3") > 0;
#endif
    }();
    return runs;
#else
    return false;
#endif
}

}  // namespace

CpuIsa cpu_isa() {
    const char* forced = std::getenv("KDRT_CPU_ISA");
    if (forced && std::strcmp(forced, "baseline") == 0) return CpuIsa::Baseline;
    return processor_runs_avx2_copy() ? CpuIsa::Avx2 : CpuIsa::Baseline;
}

const char* cpu_isa_name(CpuIsa isa) { return isa == CpuIsa::Avx2 ? "avx2" : "sse2"; }

}  // namespace kdrt::detail
