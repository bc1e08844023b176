// The cpu device's frame: rows as oneTBB tasks, camera rays in packets of
// four neighbouring pixels, Whitted shading (whitted_tracer.h) over the
// committed scene's Tracer. Compiled once per instruction set (cpu_isa.h),
// through committed_tracing.h.
#pragma once

#include "common/ms_since.h"
#include "common/tsan_fork_join.h"

#include "cpu/cpu_isa.h"
#include "cpu/run_with_progress.h"
#include "cpu/tracer.h"
#include "cpu/whitted_tracer.h"

#include <kdrt/camera.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// One frame (or a region of it) of `scene` through `tracer`.
template <class Real>
class FrameRender {
public:
    using Vec = glm::vec<3, Real>;
    static constexpr int kPacket = 4;  // neighbouring pixels of a row traced together

    FrameRender(const PreparedScene& scene, const Tracer<Real>& tracer, Real fixed_epsilon, const FrameOptions& options)
        : scene_(scene), options_(options), whitted_(scene, tracer, fixed_epsilon), tracer_(tracer),
          camera_(scene.camera, scene.settings.width, scene.settings.height), eye_(camera_.position),
          region_(options.region.value_or(PixelRect{0, 0, scene.settings.width, scene.settings.height})) {}

    // Every row of the region on `threads` workers; options.progress may cancel.
    RenderResult run(int threads) {
        result_.image = Image(region_.width, region_.height);
        if (options_.want_ids) {
            result_.ids.assign(static_cast<std::size_t>(region_.width) * region_.height, -1);
            result_.hit_t.assign(static_cast<std::size_t>(region_.width) * region_.height, 0.0f);
        }
        // One tally per row, written once when the row ends: no thread-local
        // storage from TBB's allocator, no false sharing while the row runs.
        counts_.assign(static_cast<std::size_t>(region_.height), RayCounts{});
        const auto start = std::chrono::steady_clock::now();
        if (options_.progress) {
            run_with_progress([&] { render_rows(threads); }, cancelled_,
                              [&] { return static_cast<double>(rows_done_.load()) / region_.height; },
                              options_.progress);
        } else {
            render_rows(threads);
        }
        result_.stats.render_ms = ms_since(start);
        for (const RayCounts& rc : counts_) result_.stats.rays += rc;
        return std::move(result_);
    }

private:
    // Rows are tasks on oneTBB's scheduler, in an arena of `threads` (the
    // kd-tree builder runs on the same scheduler).
    void render_rows(int threads) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            auto block = [&](const tbb::blocked_range<int>& rows) {
                for (int row = rows.begin(); row < rows.end(); ++row) render_row(row);
            };
            TsanForkJoin tsan;
            tbb::parallel_for(tbb::blocked_range<int>(0, region_.height, 1), tsan.task(block));
        });
    }

    // Row `row` of the region (frame row region.y + row), kPacket pixels at a time.
    void render_row(int row) {
        RayCounts rc;
        for (int c0 = 0; c0 < region_.width && !cancelled_.load(std::memory_order_relaxed); c0 += kPacket)
            render_pixels(row, c0, rc);
        counts_[static_cast<std::size_t>(row)] = rc;
        ++rows_done_;
    }

    // Pixels c0 .. c0 + kPacket - 1 of a region row, every sample. Each pixel
    // is computed from its frame coordinates alone, so a region's pixels equal
    // the whole frame's. Shadow and secondary rays go in packets too
    // (WhittedTracer::shade_packet); lanes past the row's end repeat its last
    // pixel, traced but not used.
    void render_pixels(int row, int c0, RayCounts& rc) {
        const int W = scene_.settings.width, H = scene_.settings.height, N = scene_.settings.samples;
        const int n = std::min(kPacket, region_.width - c0);
        const int y = region_.y + row;
        Vec sum[kPacket] = {};
        for (int s = 0; s < N; ++s) {
            double sx, sy;
            sample_offset(s, N, sx, sy);
            const auto lane_ray = [&](int k) {
                const int x = region_.x + std::min(c0 + k, region_.width - 1);
                return Ray<Real>(eye_, Vec(camera_.direction(x, y, W, H, sx, sy)));
            };
            const Ray<Real> rays[kPacket] = {lane_ray(0), lane_ray(1), lane_ray(2), lane_ray(3)};
            const Ray<Real>* lanes[kPacket] = {&rays[0], &rays[1], &rays[2], &rays[3]};
            Hit<Real> hits[kPacket];
            tracer_.closest(lanes, hits);
            Vec color[kPacket];
            whitted_.shade_packet(lanes, hits, (1u << n) - 1, 1, rc, color);
            for (int k = 0; k < n; ++k) {
                ++rc.camera;
                sum[k] += color[k];
                if (options_.want_ids && s == 0) record_id(static_cast<std::size_t>(row) * region_.width + c0 + k, hits[k]);
            }
        }
        for (int k = 0; k < n; ++k) result_.image.set(c0 + k, row, glm::vec3(sum[k] / static_cast<Real>(N)));
    }

    // The id map records the first sample's camera ray (the pixel centre when there is one sample).
    void record_id(std::size_t i, const Hit<Real>& hit) {
        result_.ids[i] = hit.id;
        result_.hit_t[i] = hit.valid() ? static_cast<float>(hit.t) : 0.0f;
    }

    const PreparedScene& scene_;
    const FrameOptions& options_;
    WhittedTracer<Real, Tracer<Real>> whitted_;
    const Tracer<Real>& tracer_;
    const CameraFrame camera_;
    const Vec eye_;
    const PixelRect region_;
    RenderResult result_;
    std::vector<RayCounts> counts_;
    std::atomic<int> rows_done_{0};
    std::atomic<bool> cancelled_{false};
};

// The frame's worker threads: options.threads, or all of the arena's.
inline int frame_threads(const FrameOptions& options) {
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    return std::clamp(threads, 1, 256);
}

template <class Real>
RenderResult render_frame(const PreparedScene& scene, const Tracer<Real>& tracer, Real fixed_epsilon,
                          const FrameOptions& options, CpuIsa isa) {
    const int threads = frame_threads(options);
    RenderResult result = FrameRender<Real>(scene, tracer, fixed_epsilon, options).run(threads);
    result.stats.features = scene.features;
    result.stats.device_name = std::string("cpu (C++ reference, ") + cpu_isa_name(isa) + ", " +
                               (sizeof(Real) == 8 ? "double" : "float") + ", " + std::to_string(threads) + " threads)";
    return result;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
