// How the SAH cost constants of KdBuildConfig were measured. The traversal is
// traverse_stack itself; its leaf visitor reports "no hit" so every ray
// walks its whole path, and the loop iterations are counted with a copy of
// the loop shape. Steps: time of the walk with empty visits / iterations.
// Tests: (time with every object tested - time of the walk) / tests.
#include "cpu/traversal_costs.h"

#include "common/ms_since.h"
#include "cpu/intersect.h"
#include "cpu/traverse_stack.h"

#include <algorithm>
#include <chrono>
#include <limits>

namespace kdrt::detail {

namespace {

// traverse_stack's loop, counting its iterations instead of timing them.
std::size_t count_steps(const KdTree& tree, const Ray<float>& ray) {
    float t0, t1;
    if (tree.nodes.empty() || !clip_to_box(ray, tree.bounds, std::numeric_limits<float>::infinity(), t0, t1))
        return 0;
    struct Entry {
        std::uint32_t node;
        float tmin, tmax;
    };
    Entry stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    std::uint32_t node = 0;
    float tmin = t0, tmax = t1;
    std::size_t steps = 0;
    for (;;) {
        ++steps;
        const KdNode& n = tree.nodes[node];
        if (!kd_is_leaf(n)) {
            float t_split;
            const SplitStep step = split_step(tree, node, ray, t_split);
            if (t_split <= tmin) {
                node = step.far_child;
            } else if (t_split >= tmax) {
                node = step.near_child;
            } else {
                stack[top++] = {step.far_child, t_split, tmax};
                node = step.near_child;
                tmax = t_split;
            }
            continue;
        }
        if (top == 0) return steps;
        --top;
        node = stack[top].node;
        tmin = stack[top].tmin;
        tmax = stack[top].tmax;
    }
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
            traverse_stack(tree, ray, std::numeric_limits<float>::infinity(),
                                   [&](const std::uint32_t* ids, std::uint32_t count) {
                                       visited += count + (count ? ids[0] : 0);
                                       return std::numeric_limits<float>::infinity();
                                   });
        walk_ms = std::min(walk_ms, ms_since(start));
        sink = sink + visited;

        std::size_t tested = 0;
        start = std::chrono::steady_clock::now();
        for (const auto& ray : rays) {
            Hit<float> best;
            traverse_stack(tree, ray, std::numeric_limits<float>::infinity(),
                                   [&](const std::uint32_t* ids, std::uint32_t count) {
                                       for (std::uint32_t i = 0; i < count; ++i) {
                                           Hit<float> h;
                                           intersect_object(g, ray, ids[i], h);
                                           best.t = std::min(best.t, h.t);
                                       }
                                       tested += count;
                                       return std::numeric_limits<float>::infinity();
                                   });
            sink = sink + static_cast<std::uint64_t>(best.t > 0.0f);
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
