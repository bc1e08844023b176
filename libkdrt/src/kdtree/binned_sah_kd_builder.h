// The default kd-tree builder: binned SAH on large nodes, the exact sweep on
// small ones, in parallel on oneTBB (see binned_sah_kd_builder.cpp).
#pragma once

#include <kdrt/kd_tree.h>

namespace kdrt::detail {

// Uses the SAH constants of config, config.sah_bins, exact_threshold,
// threads, max_depth (0: sah_automatic_max_depth), the duplication limit,
// memory budget and progress hook. Splits "perfectly" with input.clip when it
// is set. The tree is byte for byte the same for any thread count.
KdTree build_binned_sah_kd_tree(const KdBuildInput& input, const KdBuildConfig& config);

}  // namespace kdrt::detail
