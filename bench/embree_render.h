// Rendering a kdrt scene with Embree under FORMAT.md's contract: the scene is
// prepared as kdrt prepares it (kdrt::WorkingScene: working frame, float
// geometry), Embree builds its BVH over that geometry (embree_scene.h), and
// WorkingScene::shade, the cpu device's own shader, shades Embree's hits.
// The same shading over kdrt's own traversal (WorkingScene::kd_intersector)
// must give the cpu device's image: that checks the harness.
#pragma once

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "common.h"
#include "embree_scene.h"

#include <kdrt/render.h>
#include <kdrt/working_scene.h>

#include <memory>
#include <string>

namespace kdrt::bench {

// One sample per pixel centre over `intersector`, rows handed out to
// `threads` workers (0: every logical CPU) as the cpu device does. Fills the
// image, rays and render_ms, and ids / hit_t when asked.
RenderResult render_whitted(const WorkingScene& scene, const ShadingIntersector& intersector, int threads,
                            bool want_ids);

class EmbreeRenderer {
public:
    // Size and depth are taken from `options` as kdrt takes them (samples must be 1).
    EmbreeRenderer(const Scene& scene, const RenderOptions& options);

    double commit_ms() const { return embree_->commit_ms(); }  // Embree's BVH build
    const WorkingScene& prepared() const { return prepared_; }
    RenderResult render(int threads, bool want_ids) const { return render_whitted(prepared_, *embree_, threads, want_ids); }

private:
    WorkingScene prepared_;
    std::unique_ptr<EmbreeScene> embree_;
};

// `kdrt-bench embree-render`: kdrt's loader, Embree's BVH and tracing, kdrt's
// shader and image writer: a whole process that differs from kdrt-render only
// in the acceleration structure and the tracer. width, height: 0 for the scene's.
int run_embree_render(const std::string& scene_path, const std::string& out, int threads, int width, int height);

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
