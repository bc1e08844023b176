// The cpu device's AVX2 copy (cpu_isa.h, avx2_prelude.h).
#include "cpu/avx2_prelude.h"

#if KDRT_CPU_HAS_AVX2_COPY

KDRT_CPU_AVX2_BEGIN
#include "cpu/committed_tracing.h"
KDRT_CPU_AVX2_END

namespace kdrt::detail {

std::unique_ptr<CpuTracing> make_cpu_tracing_avx2(const PreparedScene& scene, AccelRef accel,
                                                  const CommitOptions& options) {
    return isa_avx2::make_committed_tracing(scene, accel, options, CpuIsa::Avx2);
}

}  // namespace kdrt::detail

#endif  // KDRT_CPU_HAS_AVX2_COPY
