// The render times the benchmarks report: the median of N renders after one
// warm-up render (which builds or loads the tree and compiles the kernels).
#pragma once

#include "stats.h"

#include <kdrt/render.h>

#include <vector>

namespace kdrt::bench {

inline double median_render_ms(const Scene& scene, const RenderOptions& options, int runs) {
    std::vector<double> ms;
    for (int run = -1; run < runs; ++run) {
        const RenderResult r = render(scene, options);
        if (run >= 0) ms.push_back(r.stats.render_ms);
    }
    return median(ms);
}

}  // namespace kdrt::bench
