// One mesh's rays and Embree's answers as raw little-endian arrays, for a
// tracer outside kdrt (bench/warp_rays.py): DIR/NAME.json names each file.
#pragma once

#include "common.h"

#include <kdrt/layout.h>
#include <kdrt/scene.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace kdrt::bench {

class RayExport {
public:
    // Writes the scene's one mesh: world-space float vertices, uint32 triangles.
    RayExport(const std::filesystem::path& dir, const Scene& scene);

    // A ray set as (origin, direction) in world space, six floats a ray.
    void rays(const std::string& set_name, std::span<const QueryRay> rays);

    // The last set's answers: closest, each ray's t (infinity where ids[i] < 0);
    // any hit, 1 or 0 a ray (ids).
    void answers(bool any, const std::vector<std::int32_t>& ids, const std::vector<float>& ts);

    // NAME.json last, once every file it names is written.
    void finish() const;

private:
    std::filesystem::path dir_;
    std::string name_;
    Json index_;
};

// Whether RayExport can write the scene: one mesh and nothing else.
bool one_mesh(const Scene& scene);

}  // namespace kdrt::bench
