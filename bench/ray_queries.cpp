#include "ray_queries.h"

#include "stats.h"

#include <tbb/task_arena.h>

#include <limits>

namespace kdrt::bench {

std::vector<QueryRay> to_query_rays(const std::vector<ShadingRay>& rays, const glm::dvec3& frame_origin) {
    std::vector<QueryRay> out(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const glm::dvec3 org = glm::dvec3(rays[i].origin) + frame_origin;
        QueryRay& q = out[i];
        for (int a = 0; a < 3; ++a) {
            q.origin[a] = static_cast<float>(org[a]);
            q.direction[a] = rays[i].direction[a];
        }
        q.t_min = 0.0f;
        q.t_max = std::numeric_limits<float>::infinity();
    }
    return out;
}

double time_intersect(const CommittedScene& scene, std::span<const QueryRay> rays, int threads, std::int32_t* ids,
                      float* ts) {
    std::vector<QueryHit> hits(rays.size());
    tbb::task_arena arena(threads);
    const Stopwatch clock;
    arena.execute([&] { intersect(scene, rays, hits); });
    const double ms = clock.ms();
    for (std::size_t i = 0; i < hits.size(); ++i) {
        ids[i] = hits[i].object == KDRT_NO_HIT ? -1 : static_cast<std::int32_t>(hits[i].object);
        ts[i] = hits[i].t;
    }
    return ms;
}

double time_occluded(const CommittedScene& scene, std::span<const QueryRay> rays, int threads, std::int32_t* ids) {
    std::vector<std::uint8_t> hit(rays.size());
    tbb::task_arena arena(threads);
    const Stopwatch clock;
    arena.execute([&] { occluded(scene, rays, hit); });
    const double ms = clock.ms();
    for (std::size_t i = 0; i < hit.size(); ++i) ids[i] = hit[i];
    return ms;
}

}  // namespace kdrt::bench
