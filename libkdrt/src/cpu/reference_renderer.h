// The C++ reference renderer (device "cpu"): FORMAT.md's camera and Whitted
// shading, written for clarity; every other device is compared with it.
#pragma once

#include "scene/prepared_scene.h"

#include <kdrt/render_options.h>

namespace kdrt::detail {

// Renders with the given tree (may be null for Traversal::None), in the
// instruction set cpu_isa() picks.
RenderResult render_reference(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options);

// The same in one instruction set (cpu_isa.h): the pictures are identical.
RenderResult render_reference_baseline(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options);
RenderResult render_reference_avx2(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options);

}  // namespace kdrt::detail
