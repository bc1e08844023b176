// A committed scene's tracing on the cpu device: one Tracer (tracer.h) over
// the scene's geometry and tree, made once for an instruction set (cpu_isa.h)
// and a precision, that renders the scene's frames and answers its ray queries.
#pragma once

#include "cpu/cpu_isa.h"
#include "device/accel.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>
#include <kdrt/commit_options.h>
#include <kdrt/frame_options.h>
#include <kdrt/layout.h>
#include <kdrt/render_result.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace kdrt::detail {

class CpuTracing {
public:
    virtual ~CpuTracing() = default;

    // One frame (render_frame.h).
    virtual RenderResult render(const FrameOptions& frame) const = 0;

    // hits[i] / occluded[i] for rays[i] (ray_query_loops.h); object ids are
    // internal (positions in SceneGeometry). The spans have equal sizes. Thread-safe.
    virtual void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const = 0;
    virtual void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const = 0;
    // Hits per ray, every hit (ray_splits, hits) and closest points
    // (kdrt/ray_query.h), with internal ids. Thread-safe.
    virtual void count_hits(std::span<const QueryRay> rays, std::span<std::uint32_t> counts) const = 0;
    virtual void count_hits_once_per_geometry(std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                                              std::span<const std::uint32_t> geometry_of) const = 0;
    virtual void all_hits(std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                          std::vector<QueryHit>& hits) const = 0;
    virtual void closest_points(std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) const = 0;

    // The scene's objects moved and its BVH was refit in place: what the
    // tracing copied of them (Tracer::refit) follows.
    virtual void refit() = 0;

    // The bytes of the tracer's packed copy of the leaves (and a BVH's nodes); 0 where it keeps none.
    virtual std::uint64_t packed_bytes() const = 0;
};

// The tracing of `scene` through `accel` (neither structure for Traversal::None) and the
// commit options (traversal and accuracy), in
// instruction set `isa`. The scene and structures must outlive it.
std::unique_ptr<CpuTracing> make_cpu_tracing(CpuIsa isa, const PreparedScene& scene, AccelRef accel,
                                             const CommitOptions& options);

// make_cpu_tracing's work in each instruction set.
std::unique_ptr<CpuTracing> make_cpu_tracing_baseline(const PreparedScene& scene, AccelRef accel,
                                                      const CommitOptions& options);
std::unique_ptr<CpuTracing> make_cpu_tracing_avx2(const PreparedScene& scene, AccelRef accel,
                                                  const CommitOptions& options);

}  // namespace kdrt::detail
