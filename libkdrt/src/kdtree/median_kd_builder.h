// The spatial-median kd-tree builder of the 2016 study (see median_kd_builder.cpp).
#pragma once

#include <kdrt/kd_tree.h>

namespace kdrt::detail {

// Uses config.max_depth (0: 10) and config.median_max_duplication; the SAH
// constants and input.clip are ignored (the study split object boxes).
// Builds nodes, leaves and leaf lists; no ropes.
KdTree build_median_kd_tree(const KdBuildInput& input, const KdBuildConfig& config);

}  // namespace kdrt::detail
