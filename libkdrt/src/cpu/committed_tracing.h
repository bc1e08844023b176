// CpuTracing (cpu_tracing.h) in one instruction set: the Tracer made at
// commit, and the frame and query loops over it. Compiled once per
// instruction set (cpu_isa.h): cpu_tracing.cpp and cpu_tracing_avx2.cpp.
#pragma once

#include "cpu/cpu_tracing.h"
#include "cpu/ray_query_loops.h"
#include "cpu/render_frame.h"
#include "cpu/tracer.h"

#include <memory>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// The intersection tests the accuracy knobs ask for.
inline IntersectConfig intersect_config(const AccuracyOptions& accuracy) {
    IntersectConfig config;
    config.moller = accuracy.triangle_test == TriangleTest::MollerTrumbore;
    config.textbook = accuracy.sphere_test == SphereTest::Textbook;
    return config;
}

template <class Real>
class CommittedTracing final : public CpuTracing {
public:
    CommittedTracing(const PreparedScene& scene, AccelRef accel, const CommitOptions& options, CpuIsa isa)
        : scene_(scene), tracer_(scene.geometry<Real>(), accel, options.traversal, intersect_config(options.accuracy)),
          fixed_epsilon_(options.accuracy.self_intersection == SelfIntersection::FixedEpsilon
                             ? static_cast<Real>(options.accuracy.fixed_epsilon)
                             : Real(0)),
          isa_(isa) {}

    RenderResult render(const FrameOptions& frame) const override {
        return render_frame(scene_, tracer_, fixed_epsilon_, frame, isa_);
    }
    void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const override {
        intersect_rays(tracer_, scene_.frame_origin, rays, hits);
    }
    void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const override {
        occluded_rays(tracer_, scene_.frame_origin, rays, occluded);
    }
    void count_hits(std::span<const QueryRay> rays, std::span<std::uint32_t> counts) const override {
        count_rays(tracer_, scene_.frame_origin, rays, counts);
    }
    void count_hits_once_per_geometry(std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                                      std::span<const std::uint32_t> geometry_of) const override {
        count_rays_once_per_geometry(tracer_, scene_.frame_origin, rays, counts, geometry_of);
    }
    void all_hits(std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                  std::vector<QueryHit>& hits) const override {
        every_hit_rays(tracer_, scene_.frame_origin, rays, splits, hits);
    }
    void closest_points(std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) const override {
        closest_point_queries(tracer_, scene_.frame_origin, points, out);
    }
    void refit() override { tracer_.refit(); }
    std::uint64_t packed_bytes() const override { return tracer_.packed_bytes(); }

private:
    const PreparedScene& scene_;
    Tracer<Real> tracer_;
    Real fixed_epsilon_;  // > 0: the fixed-epsilon knob's absolute offset, without self-exclusion
    CpuIsa isa_;
};

inline std::unique_ptr<CpuTracing> make_committed_tracing(const PreparedScene& scene, AccelRef accel,
                                                          const CommitOptions& options, CpuIsa isa) {
    if (options.accuracy.precision == Precision::Double)
        return std::make_unique<CommittedTracing<double>>(scene, accel, options, isa);
    return std::make_unique<CommittedTracing<float>>(scene, accel, options, isa);
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
