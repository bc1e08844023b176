// The ray queries' AVX2 copy (cpu_isa.h, avx2_prelude.h).
#include "cpu/avx2_prelude.h"

#if KDRT_CPU_HAS_AVX2_COPY

KDRT_CPU_AVX2_BEGIN
#include "cpu/ray_query_tracer.h"
KDRT_CPU_AVX2_END

namespace kdrt::detail {

void ray_queries_intersect_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    isa_avx2::intersect_rays(setup, rays, hits);
}

void ray_queries_occluded_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                               std::span<std::uint8_t> occluded) {
    isa_avx2::occluded_rays(setup, rays, occluded);
}

}  // namespace kdrt::detail

#endif  // KDRT_CPU_HAS_AVX2_COPY
