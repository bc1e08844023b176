// The builders' front door: validate the configuration once, then dispatch.
#include "kdtree/binned_sah_kd_builder.h"
#include "kdtree/median_kd_builder.h"
#include "kdtree/sah_kd_builder.h"

#include <kdrt/kd_tree.h>

namespace kdrt {

KdTree build_kd_tree(const KdBuildInput& input, const KdBuildConfig& given) {
    given.validate();
    const KdBuildConfig config = given.with_triangle_cost(KdBuildConfig::kGenericTriangleCost);
    switch (config.builder) {
        case KdBuilderKind::Median: return detail::build_median_kd_tree(input, config);
        case KdBuilderKind::SahExact: return detail::build_exact_sah_kd_tree(input, config);
        case KdBuilderKind::Sah: break;
    }
    return detail::build_binned_sah_kd_tree(input, config);
}

}  // namespace kdrt
