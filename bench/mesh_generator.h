// Generated test scenes for the build benchmark: a tessellated torus of about
// N triangles (shared vertices, no normals), seen by a camera from above at
// an angle, with one light, as a kdrt::Scene.
#pragma once

#include <kdrt/scene.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace kdrt::bench {

// The torus has 2 * nu * nv triangles with nu = 2 nv, the nearest to `triangles`.
Scene make_torus_scene(std::size_t triangles);

// A terrain: a (points x points) grid over [-1, 1]^2 (2 (points - 1)^2
// triangles), heights from smooth waves plus a hashed per-vertex noise, so the
// same `points` always gives the same mesh; camera above it at an angle.
Scene make_heightfield_scene(std::uint32_t points);

// "100k" -> 100000, "4M" -> 4000000, "1234" -> 1234; throws kdrt::Error(InvalidArgument).
std::size_t parse_count(const std::string& text);

}  // namespace kdrt::bench
