// The reference renderer's AVX2 copy (cpu_isa.h, avx2_prelude.h).
#include "cpu/avx2_prelude.h"

#if KDRT_CPU_HAS_AVX2_COPY

KDRT_CPU_AVX2_BEGIN
#include "cpu/render_frame.h"
KDRT_CPU_AVX2_END

namespace kdrt::detail {

RenderResult render_reference_avx2(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                                   const FrameOptions& frame) {
    return isa_avx2::render_frame_in(scene, tree, commit, frame, CpuIsa::Avx2);
}

}  // namespace kdrt::detail

#endif  // KDRT_CPU_HAS_AVX2_COPY
