// Our scenes in POV-Ray 3.7's scene language, for a timing comparison with
// a classic Whitted ray tracer (not for pixel equality). The mapping:
//  - camera: POV-Ray is left-handed, FORMAT.md's camera right-handed
//    (right = forward x up), so `right -x*aspect` flips the handedness; the
//    horizontal `angle` is 2 atan(aspect tan(fov_y / 2)), matching the pinhole;
//  - point lights without fall-off; background; ambient through
//    global ambient_light and finish ambient kd (POV multiplies by the pigment);
//  - finish: diffuse kd, phong ks with phong_size n (white highlights),
//    reflection kr; glass: pigment transmit kt and interior ior;
//  - max_trace_level = the scene's max_depth, assumed_gamma 1 (linear, as ours).
// Differences that remain: POV-Ray lets light through transparent objects for
// shadows and scales a transparent surface's diffuse term by (1 - kt).
#pragma once

#include <kdrt/scene.h>

#include <filesystem>
#include <string>

namespace kdrt::bench {

// width, height: the image the camera is set up for (0: the scene's).
std::string to_povray(const Scene& scene, int width = 0, int height = 0);
void write_povray(const Scene& scene, const std::filesystem::path& path, int width = 0, int height = 0);

}  // namespace kdrt::bench
