#include "embree_render.h"

#ifdef KDRT_BENCH_HAVE_EMBREE

#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/scene_loader.h>

#include <cstdio>

namespace kdrt::bench {

RenderResult render_whitted(const WorkingScene& scene, const ShadingIntersector& intersector, int threads,
                            bool want_ids) {
    const int W = scene.width(), H = scene.height();
    RenderResult result;
    result.image = Image(W, H);
    if (want_ids) {
        result.ids.assign(static_cast<std::size_t>(W) * H, -1);
        result.hit_t.assign(static_cast<std::size_t>(W) * H, 0.0f);
    }
    const int workers = worker_count(threads);
    std::vector<RayCounts> counts(static_cast<std::size_t>(workers));
    const Stopwatch clock;
    parallel_chunks(static_cast<std::size_t>(H), workers, 1, [&](std::size_t y0, std::size_t y1, int worker) {
        RayCounts& rc = counts[static_cast<std::size_t>(worker)];
        for (int y = static_cast<int>(y0); y < static_cast<int>(y1); ++y)
            for (int x = 0; x < W; ++x) {
                const ShadingRay ray = scene.camera_ray(x, y);
                ++rc.camera;
                const ShadingHit hit = intersector.closest(ray);
                result.image.set(x, y, scene.shade(ray, hit, intersector, rc));
                if (!want_ids || hit.object < 0) continue;
                const std::size_t i = static_cast<std::size_t>(y) * W + x;
                result.ids[i] = static_cast<std::int32_t>(scene.object_id(static_cast<std::uint32_t>(hit.object)));
                result.hit_t[i] = hit.t;
            }
    });
    result.stats.render_ms = clock.ms();
    for (const RayCounts& rc : counts) result.stats.rays += rc;
    result.stats.device_name = embree_version() + " (" + std::to_string(workers) + " threads)";
    return result;
}

EmbreeRenderer::EmbreeRenderer(const Scene& scene, const RenderOptions& options) : prepared_(scene, options) {
    if (prepared_.samples() != 1) throw Error(ErrorCode::Unsupported, "the Embree renderer traces one sample per pixel");
    embree_ = std::make_unique<EmbreeScene>(prepared_, true);
}

int run_embree_render(const std::string& scene_path, const std::string& out, int threads, int width, int height) {
    RenderOptions options;
    options.frame.width = width;
    options.frame.height = height;
    const EmbreeRenderer renderer(load_scene(scene_path), options);
    const RenderResult r = renderer.render(threads, false);
    write_image(out, r.image);
    std::fprintf(stderr, "embree-render: %s: BVH build %.1f ms, render %.1f ms\n", out.c_str(), renderer.commit_ms(),
                 r.stats.render_ms);
    return 0;
}

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
