// The C++ reference renderer's frame: rows as oneTBB tasks, camera rays in
// packets of four neighbouring pixels, Whitted shading (whitted_tracer.h).
// Compiled once per instruction set (cpu_isa.h): reference_renderer.cpp and
// reference_renderer_avx2.cpp.
#pragma once

#include "common/ms_since.h"
#include "common/tsan_fork_join.h"

#include "cpu/cpu_isa.h"
#include "cpu/run_with_progress.h"
#include "cpu/scene_tracer.h"
#include "cpu/whitted_tracer.h"

#include <kdrt/camera.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real>
RenderResult render_frame(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                          const FrameOptions& options, CpuIsa isa) {
    using Vec = glm::vec<3, Real>;
    const int W = scene.settings.width, H = scene.settings.height, N = scene.settings.samples;
    const AccuracyOptions& accuracy = commit.accuracy;
    IntersectConfig config;
    config.moller = accuracy.triangle_test == TriangleTest::MollerTrumbore;
    config.textbook = accuracy.sphere_test == SphereTest::Textbook;
    SceneTracer<Real> tracer(scene.geometry<Real>(), tree, commit.traversal, config);
    const Real fixed_epsilon = accuracy.self_intersection == SelfIntersection::FixedEpsilon
                                   ? static_cast<Real>(accuracy.fixed_epsilon)
                                   : Real(0);
    WhittedTracer<Real, SceneTracer<Real>> whitted(scene, tracer, fixed_epsilon);
    const CameraFrame cam(scene.camera, W, H);
    const Vec eye(cam.position);
    // The pixels asked for (checked by the dispatch layer): each is computed
    // from its frame coordinates alone, so a region's pixels equal the frame's.
    const PixelRect region = options.region.value_or(PixelRect{0, 0, W, H});
    const int RW = region.width, RH = region.height;

    RenderResult result;
    result.image = Image(RW, RH);
    if (options.want_ids) {
        result.ids.assign(static_cast<std::size_t>(RW) * RH, -1);
        result.hit_t.assign(static_cast<std::size_t>(RW) * RH, 0.0f);
    }

    // Rows are tasks on oneTBB's scheduler, in an arena of `threads` (the
    // kd-tree builder runs on the same scheduler).
    int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    threads = std::clamp(threads, 1, 256);
    std::atomic<int> rows_done{0};
    std::atomic<bool> cancelled{false};
    // One tally per row, written once when the row ends: no thread-local
    // storage from TBB's allocator, no false sharing while the row runs.
    std::vector<RayCounts> counts(static_cast<std::size_t>(RH));

    // Row `row` of the region (frame row region.y + row). Camera rays go in
    // packets of kPacket neighbouring pixels of a row, and so do their shadow
    // and secondary rays (WhittedTracer::shade_packet; SceneTracer's packet
    // queries fall back to single rays when the directions' signs differ).
    constexpr int kPacket = 4;
    auto render_row = [&](int row) {
        RayCounts rc;
        const auto store = [&] { counts[static_cast<std::size_t>(row)] = rc; };
        const int y = region.y + row;
        for (int c0 = 0; c0 < RW; c0 += kPacket) {
            if (cancelled.load(std::memory_order_relaxed)) return store();
            const int n = std::min(kPacket, RW - c0);
            Vec sum[kPacket] = {};
            for (int s = 0; s < N; ++s) {
                double sx, sy;
                sample_offset(s, N, sx, sy);
                // Lanes past the region row's end repeat its last pixel, traced but not used.
                const auto lane_ray = [&](int k) {
                    const int x = region.x + std::min(c0 + k, RW - 1);
                    return Ray<Real>(eye, Vec(cam.direction(x, y, W, H, sx, sy)));
                };
                const Ray<Real> rays[kPacket] = {lane_ray(0), lane_ray(1), lane_ray(2), lane_ray(3)};
                const Ray<Real>* lanes[kPacket] = {&rays[0], &rays[1], &rays[2], &rays[3]};
                Hit<Real> hits[kPacket];
                tracer.closest(lanes, hits);
                Vec color[kPacket];
                whitted.shade_packet(lanes, hits, (1u << n) - 1, 1, rc, color);
                for (int k = 0; k < n; ++k) {
                    ++rc.camera;
                    sum[k] += color[k];
                    // The id map records the first sample's camera ray (the pixel centre when N = 1).
                    if (options.want_ids && s == 0) {
                        const std::size_t i = static_cast<std::size_t>(row) * RW + c0 + k;
                        result.ids[i] = hits[k].id;
                        result.hit_t[i] = hits[k].valid() ? static_cast<float>(hits[k].t) : 0.0f;
                    }
                }
            }
            for (int k = 0; k < n; ++k) result.image.set(c0 + k, row, glm::vec3(sum[k] / static_cast<Real>(N)));
        }
        store();
        ++rows_done;
    };

    const auto start = std::chrono::steady_clock::now();
    tbb::task_arena arena(threads);
    auto render_rows = [&] {
        arena.execute([&] {
            auto block = [&](const tbb::blocked_range<int>& rows) {
                for (int y = rows.begin(); y < rows.end(); ++y) render_row(y);
            };
            TsanForkJoin tsan;
            tbb::parallel_for(tbb::blocked_range<int>(0, RH, 1), tsan.task(block));
        });
    };
    if (options.progress) {
        run_with_progress(render_rows, cancelled, [&] { return static_cast<double>(rows_done.load()) / RH; },
                          options.progress);
    } else {
        render_rows();
    }
    RenderStats& stats = result.stats;
    stats.render_ms = ms_since(start);
    for (const RayCounts& rc : counts) stats.rays += rc;
    stats.features = scene.features;
    stats.device_name = std::string("cpu (C++ reference, ") + cpu_isa_name(isa) + ", " +
                        (sizeof(Real) == 8 ? "double" : "float") + ", " + std::to_string(threads) + " threads)";
    return result;
}

inline RenderResult render_frame_in(const PreparedScene& scene, const KdTree* tree, const CommitOptions& commit,
                                    const FrameOptions& frame, CpuIsa isa) {
    if (commit.accuracy.precision == Precision::Double) return render_frame<double>(scene, tree, commit, frame, isa);
    return render_frame<float>(scene, tree, commit, frame, isa);
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
