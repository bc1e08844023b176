// The BVH traversal's AVX2 copy (cpu_isa.h) returns brute force's hits, as
// the baseline copy does (test_bvh_traversal.cpp): the checks of
// bvh_traversal_checks.h compiled under the AVX2 target, as the cpu device's
// *_avx2.cpp files compile its traversals.
#include "cpu/avx2_prelude.h"

#if KDRT_CPU_HAS_AVX2_COPY

#include "bvh_test_scenes.h"

#include "bvh/bvh.h"
#include "bvh/bvh_build.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>
#include <vector>

KDRT_CPU_AVX2_BEGIN
#include "bvh_traversal_checks.h"
KDRT_CPU_AVX2_END

using namespace kdrt;
using namespace kdrt::detail;

namespace {

template <class Real>
void check_avx2_copy(const Scene& scene, std::uint32_t seed) {
    const PreparedScene p = test::prepare(scene, sizeof(Real) == sizeof(double) ? Precision::Double : Precision::Float);
    const SceneGeometry<Real>& g = p.geometry<Real>();
    const std::vector<Aabb> boxes = test::tight_bounds(g);
    BvhBuildConfig config;
    config.max_leaf_size = 4;
    const BvhBuildInput in{boxes, static_cast<std::uint32_t>(g.spheres.size())};
    const WideBvhN<8> w8 = build_wide_bvh<8>(in, config);
    const WideBvhN<4> w4 = build_wide_bvh<4>(in, config);
    const auto rays = isa_avx2::bvh_rays(g, p.bounds, w8, seed);
    for (bool batched : {false, true}) {
        for (const isa_avx2::TraversalReport& r :
             {isa_avx2::check_wide_bvh(g, w8, rays, batched), isa_avx2::check_wide_bvh(g, w4, rays, batched)}) {
            INFO((sizeof(Real) == 8 ? "double" : "float") << (batched ? ", batched" : "") << ": " << r.rays
                                                          << " rays, " << r.hits << " hits; first mismatch: " << r.first);
            CHECK(r.hits > r.rays / 10);
            CHECK(r.mismatches == 0);
            CHECK(r.blocked_mismatches == 0);
        }
    }
}

}  // namespace

TEST_CASE("bvh traversal: the AVX2 copy equals brute force", "[bvh][traversal]") {
    if (cpu_isa() != CpuIsa::Avx2) {
        WARN("this processor runs the baseline copy only: the AVX2 copy is not tested");
        return;
    }
    for (std::uint32_t seed : {31u, 32u}) {
        const Scene s = test::bvh_hard_scene(seed);
        check_avx2_copy<float>(s, seed);
        check_avx2_copy<double>(s, seed + 1);
    }
}

#endif  // KDRT_CPU_HAS_AVX2_COPY
