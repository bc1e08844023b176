#include "cpu/committed_tracing.h"

namespace kdrt::detail {

std::unique_ptr<CpuTracing> make_cpu_tracing_baseline(const PreparedScene& scene, AccelRef accel,
                                                      const CommitOptions& options) {
    return make_committed_tracing(scene, accel, options, CpuIsa::Baseline);
}

std::unique_ptr<CpuTracing> make_cpu_tracing(CpuIsa isa, const PreparedScene& scene, AccelRef accel,
                                             const CommitOptions& options) {
#if KDRT_CPU_HAS_AVX2_COPY
    if (isa == CpuIsa::Avx2) return make_cpu_tracing_avx2(scene, accel, options);
#else
    (void)isa;
#endif
    return make_cpu_tracing_baseline(scene, accel, options);
}

}  // namespace kdrt::detail
