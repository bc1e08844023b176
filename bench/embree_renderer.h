// Rendering a kdrt scene with Embree under FORMAT.md's contract: the scene is
// prepared exactly as kdrt prepares it (kdrt::WorkingScene: working frame,
// float geometry, features), Embree builds its BVH over that geometry, and
// WorkingScene::shade shades, multi-threaded like the cpu device.
#pragma once

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "embree_scene.h"

#include <kdrt/render.h>
#include <kdrt/scene.h>

#include <memory>
#include <string>

namespace kdrt::bench {

class EmbreeRenderer {
public:
    // Size, depth and samples are taken from `options` as kdrt does (samples must be 1).
    EmbreeRenderer(const Scene& scene, const RenderOptions& options);

    double commit_ms() const { return embree_->commit_ms(); }
    const WorkingScene& prepared() const { return prepared_; }

    // threads: 0 = every logical CPU, as the cpu device. build_ms is the commit time.
    RenderResult render(int threads, bool want_ids) const;

private:
    WorkingScene prepared_;
    std::unique_ptr<EmbreeScene> embree_;
};

// kdrt-bench embree-render: loads the scene with kdrt's loader, renders it with
// Embree and writes the image with kdrt's writer, so a whole-process timing
// against kdrt-render differs only in the acceleration structure and tracer.
int run_embree_render(const std::string& scene_path, const std::string& out, int threads);

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
