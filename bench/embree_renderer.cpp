#include "embree_renderer.h"

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "whitted_renderer.h"

#include <kdrt/error.h>

namespace kdrt::bench {

EmbreeRenderer::EmbreeRenderer(const Scene& scene, const RenderOptions& options)
    : prepared_(std::make_unique<detail::PreparedScene>(detail::prepare_scene(scene, options))) {
    if (prepared_->settings.samples != 1)
        throw Error(ErrorCode::Unsupported, "the Embree renderer traces one sample per pixel");
    embree_ = std::make_unique<EmbreeScene>(prepared_->geometry_f, true);
}

RenderResult EmbreeRenderer::render(int threads, bool want_ids) const {
    RenderResult r = render_whitted(*prepared_, *embree_, threads, want_ids, embree_version());
    r.build_ms = embree_->commit_ms();
    return r;
}

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
