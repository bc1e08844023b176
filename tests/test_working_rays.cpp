// The cpu device's query setup: a packet's four rays set up at once
// (working_rays) give working_ray's rays bit for bit and refuse the same
// ones (working_rays_checks.h), in the baseline copy here and in the AVX2
// copy in test_working_rays_avx2.cpp.
#include "working_rays_checks.h"

#include <catch2/catch.hpp>

using namespace kdrt::detail;

TEST_CASE("query setup: four rays at once are working_ray's, bit for bit", "[query][lanes]") {
    const glm::dvec3 frame_origin(12.5, -3.25, 1e3);
    const std::vector<kdrt::QueryRay> rays = setup_test_rays(41);
    for (const SetupReport& r : {check_working_rays<float>(rays, frame_origin),
                                 check_working_rays<double>(rays, frame_origin)}) {
        INFO(r.valid << " valid, " << r.invalid << " invalid; first mismatch: " << r.first);
        CHECK(r.mismatches == 0);
        CHECK(r.valid > 2 * r.invalid);
        CHECK(r.invalid > 100);
    }
}
