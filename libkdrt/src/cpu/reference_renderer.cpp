#include "cpu/reference_renderer.h"

#include "cpu/render_frame.h"

namespace kdrt::detail {

RenderResult render_reference_baseline(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                                       const FrameOptions& frame) {
    return render_frame_in(scene, tree, commit, frame, CpuIsa::Baseline);
}

RenderResult render_reference(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                              const FrameOptions& frame) {
#if KDRT_CPU_HAS_AVX2_COPY
    if (cpu_isa() == CpuIsa::Avx2) return render_reference_avx2(scene, tree, commit, frame);
#endif
    return render_reference_baseline(scene, tree, commit, frame);
}

}  // namespace kdrt::detail
