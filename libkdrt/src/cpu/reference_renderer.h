// The C++ reference renderer (device "cpu"): FORMAT.md's camera and Whitted
// shading, written for clarity; every other device is compared with it.
#pragma once

#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>

namespace kdrt::detail {

// Renders a frame of the scene committed with `commit`, with the given tree
// (may be null for Traversal::None), in the instruction set cpu_isa() picks.
RenderResult render_reference(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                              const FrameOptions& frame);

// The same in one instruction set (cpu_isa.h): the pictures are identical.
RenderResult render_reference_baseline(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                                       const FrameOptions& frame);
RenderResult render_reference_avx2(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                                   const FrameOptions& frame);

}  // namespace kdrt::detail
