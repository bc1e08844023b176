// How the SAH cost constants of KdBuildConfig are measured. The traversal is
// traverse_stack itself; its leaf visitor reports "no hit" so every ray walks
// its whole path, and its step hook counts the loop's iterations. Steps: time
// of the walk with empty visits / iterations. Tests: (time with every object
// tested - time of the walk) / tests.
#include "cpu/traversal_costs.h"

#include "common/ms_since.h"
#include "cpu/hit_window.h"
#include "cpu/traverse_stack.h"

#include <algorithm>
#include <chrono>
#include <limits>

namespace kdrt::detail {

namespace {

constexpr float kNoHit = std::numeric_limits<float>::infinity();

// The iterations of traverse_stack's loop over all of the ray's path.
std::size_t count_steps(const KdTree& tree, const Ray<float>& ray) {
    std::size_t steps = 0;
    traverse_stack(tree, ray, kNoHit, [](const std::uint32_t*, std::uint32_t) { return kNoHit; }, [&] { ++steps; });
    return steps;
}

}  // namespace

TraversalCosts probe_traversal_costs(const SceneGeometry<float>& g, const KdTree& tree,
                                     const std::vector<Ray<float>>& rays, int runs) {
    std::size_t steps = 0, tests = 0;
    for (const auto& ray : rays) steps += count_steps(tree, ray);
    double walk_ms = std::numeric_limits<double>::infinity(), test_ms = walk_ms;
    volatile std::uint64_t sink = 0;  // keeps the empty walk from being optimised away
    for (int r = 0; r < std::max(runs, 1); ++r) {
        std::uint64_t visited = 0;
        auto start = std::chrono::steady_clock::now();
        for (const auto& ray : rays)
            traverse_stack(tree, ray, kNoHit, [&](const std::uint32_t* ids, std::uint32_t count) {
                visited += count + (count ? ids[0] : 0);
                return kNoHit;
            });
        walk_ms = std::min(walk_ms, ms_since(start));
        sink = sink + visited;

        std::size_t tested = 0;
        start = std::chrono::steady_clock::now();
        for (const auto& ray : rays) {
            float nearest = kNoHit;
            traverse_stack(tree, ray, kNoHit, [&](const std::uint32_t* ids, std::uint32_t count) {
                for (std::uint32_t i = 0; i < count; ++i) {
                    Hit<float> h;
                    if (test_object(g, ray, ids[i], OpenWindow<float>{}, IntersectConfig{}, h))
                        nearest = std::min(nearest, h.t);
                }
                tested += count;
                return kNoHit;
            });
            sink = sink + static_cast<std::uint64_t>(nearest > 0.0f);
        }
        test_ms = std::min(test_ms, ms_since(start));
        tests = tested;
    }
    TraversalCosts p;
    const double n = static_cast<double>(std::max<std::size_t>(rays.size(), 1));
    p.steps_per_ray = static_cast<double>(steps) / n;
    p.tests_per_ray = static_cast<double>(tests) / n;
    p.ns_per_step = steps ? walk_ms * 1e6 / static_cast<double>(steps) : 0.0;
    p.ns_per_test = tests ? (test_ms - walk_ms) * 1e6 / static_cast<double>(tests) : 0.0;
    return p;
}

}  // namespace kdrt::detail
