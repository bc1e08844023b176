#include "cpu/reference_renderer.h"

#include "cpu/render_frame.h"

namespace kdrt::detail {

RenderResult render_reference_baseline(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options) {
    return render_frame_in(scene, tree, options, CpuIsa::Baseline);
}

RenderResult render_reference(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options) {
#if KDRT_CPU_HAS_AVX2_COPY
    if (cpu_isa() == CpuIsa::Avx2) return render_reference_avx2(scene, tree, options);
#endif
    return render_reference_baseline(scene, tree, options);
}

}  // namespace kdrt::detail
