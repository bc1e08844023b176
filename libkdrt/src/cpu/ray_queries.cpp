#include "cpu/ray_queries.h"

#include "cpu/ray_query_tracer.h"

#include <kdrt/error.h>

#include <numeric>

namespace kdrt::detail {

void ray_queries_intersect_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                    std::span<QueryHit> hits) {
    intersect_rays(setup, rays, hits);
}

void ray_queries_occluded_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                   std::span<std::uint8_t> occluded) {
    occluded_rays(setup, rays, occluded);
}

CpuRayQueries::CpuRayQueries(const PreparedScene& scene, const KdTree* tree, const CommitOptions& options)
    : scene_(scene),
      tree_(tree),
      traversal_(options.traversal),
      precision_(options.accuracy.precision),
      moller_(options.accuracy.triangle_test == TriangleTest::MollerTrumbore),
      textbook_(options.accuracy.sphere_test == SphereTest::Textbook) {
    if (traversal_ == Traversal::None) {
        all_ids_.resize(scene.geometry_f.object_count());
        std::iota(all_ids_.begin(), all_ids_.end(), 0u);
    } else if (!tree_) {
        throw Error(ErrorCode::InvalidArgument, "ray queries: the traversal needs a kd-tree");
    } else if (traversal_ == Traversal::Ropes && !tree_->has_ropes()) {
        throw Error(ErrorCode::InvalidArgument, "ray queries: the ropes traversal needs a kd-tree with ropes");
    }
}

void CpuRayQueries::intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const {
    const RayQuerySetup setup{scene_, tree_, traversal_, precision_, moller_, textbook_, all_ids_};
#if KDRT_CPU_HAS_AVX2_COPY
    if (cpu_isa() == CpuIsa::Avx2) return ray_queries_intersect_avx2(setup, rays, hits);
#endif
    ray_queries_intersect_baseline(setup, rays, hits);
}

void CpuRayQueries::occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const {
    const RayQuerySetup setup{scene_, tree_, traversal_, precision_, moller_, textbook_, all_ids_};
#if KDRT_CPU_HAS_AVX2_COPY
    if (cpu_isa() == CpuIsa::Avx2) return ray_queries_occluded_avx2(setup, rays, occluded);
#endif
    ray_queries_occluded_baseline(setup, rays, occluded);
}

}  // namespace kdrt::detail
