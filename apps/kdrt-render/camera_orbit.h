// --frames N: a camera path of N frames orbiting the scene's camera around its
// look_at point, about the camera's up axis, one full turn; frame 0 is the
// scene's own camera. Pure arithmetic, so every process (every cluster rank)
// computes the same camera for a frame.
#pragma once

#include <kdrt/scene.h>

namespace kdrt::cli {

// The camera of frame `frame` of `frames` (0 <= frame < frames).
Camera orbit_camera(const Camera& camera, int frame, int frames);

}  // namespace kdrt::cli
