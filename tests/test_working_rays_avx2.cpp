// The query setup's AVX2 copy (cpu_isa.h): working_rays gives working_ray's
// rays bit for bit, as in the baseline copy (test_working_rays.cpp).
#include "cpu/avx2_prelude.h"

#if KDRT_CPU_HAS_AVX2_COPY

#include "device/query_misses.h"

#include <glm/vec3.hpp>

#include <catch2/catch.hpp>

#include <cstring>
#include <random>
#include <vector>

KDRT_CPU_AVX2_BEGIN
#include "working_rays_checks.h"
KDRT_CPU_AVX2_END

using namespace kdrt;
using namespace kdrt::detail;

TEST_CASE("query setup: the AVX2 copy's four rays at once are working_ray's, bit for bit", "[query][lanes]") {
    if (cpu_isa() != CpuIsa::Avx2) {
        WARN("this processor runs the baseline copy only: the AVX2 copy is not tested");
        return;
    }
    const glm::dvec3 frame_origin(12.5, -3.25, 1e3);
    const std::vector<QueryRay> rays = isa_avx2::setup_test_rays(41);
    for (const isa_avx2::SetupReport& r : {isa_avx2::check_working_rays<float>(rays, frame_origin),
                                           isa_avx2::check_working_rays<double>(rays, frame_origin)}) {
        INFO(r.valid << " valid, " << r.invalid << " invalid; first mismatch: " << r.first);
        CHECK(r.mismatches == 0);
        CHECK(r.valid > 2 * r.invalid);
        CHECK(r.invalid > 100);
    }
}

#endif  // KDRT_CPU_HAS_AVX2_COPY
