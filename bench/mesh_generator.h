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

// High depth complexity: `layers` wavy sheets of a 64 x 64 quad grid (8192
// triangles each), stacked 0.02 apart in y and seen nearly edge-on, so that a
// camera ray crosses many layers' boxes before its hit (the case where
// Vinkler et al. 2016 found kd-trees faster than BVHs).
Scene make_layers_scene(std::uint32_t layers);

// Writes a generated scene (one mesh, as make_*_scene return) as files:
// DIR/NAME.obj and DIR/NAME.json referring to it, for whole-process timings of
// kdrt-render and of `kdrt-bench embree-render`. Returns the JSON file's path.
std::string write_scene_files(const Scene& scene, const std::string& dir);

// "torus:1M", "heightfield:1001" (grid points per side) or "layers:32" (the count may be left out) -> the scene.
Scene make_generated_scene(const std::string& spec);

// "100k" -> 100000, "4M" -> 4000000, "1234" -> 1234; throws kdrt::Error(InvalidArgument).
std::size_t parse_count(const std::string& text);

}  // namespace kdrt::bench
