#include "cpu/committed_tracing.h"

namespace kdrt::detail {

std::unique_ptr<CpuTracing> make_cpu_tracing_baseline(const PreparedScene& scene, const KdTree* tree,
                                                      const CommitOptions& options) {
    return make_committed_tracing(scene, tree, options, CpuIsa::Baseline);
}

std::unique_ptr<CpuTracing> make_cpu_tracing(CpuIsa isa, const PreparedScene& scene, const KdTree* tree,
                                             const CommitOptions& options) {
#if KDRT_CPU_HAS_AVX2_COPY
    if (isa == CpuIsa::Avx2) return make_cpu_tracing_avx2(scene, tree, options);
#else
    (void)isa;
#endif
    return make_cpu_tracing_baseline(scene, tree, options);
}

}  // namespace kdrt::detail
