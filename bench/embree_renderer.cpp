#include "embree_renderer.h"

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "whitted_renderer.h"

#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/scene_loader.h>

#include <cstdio>

namespace kdrt::bench {

EmbreeRenderer::EmbreeRenderer(const Scene& scene, const RenderOptions& options)
    : prepared_(scene, options) {
    if (prepared_.samples() != 1) throw Error(ErrorCode::Unsupported, "the Embree renderer traces one sample per pixel");
    embree_ = std::make_unique<EmbreeScene>(prepared_, true);
}

RenderResult EmbreeRenderer::render(int threads, bool want_ids) const {
    RenderResult r = render_whitted(prepared_, *embree_, threads, want_ids, embree_version());
    r.stats.build_ms = embree_->commit_ms();
    return r;
}

int run_embree_render(const std::string& scene_path, const std::string& out, int threads) {
    const Scene scene = load_scene(scene_path);
    const EmbreeRenderer renderer(scene, RenderOptions{});
    const RenderResult r = renderer.render(threads, false);
    write_image(out, r.image);
    std::fprintf(stderr, "embree-render: %s: build %.1f ms, render %.1f ms\n", out.c_str(), r.stats.build_ms, r.stats.render_ms);
    return 0;
}

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
