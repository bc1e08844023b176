// kdrt::validate() in two parts: what shading reads (camera, settings,
// materials, lights), checked on every CommittedScene::update(), and the
// objects (spheres, triangles, meshes), checked only when they changed.
// validate() runs both, in this order, so the first error is the same.
#pragma once

#include <kdrt/scene.h>

namespace kdrt::detail {

// Throws kdrt::Error(InvalidScene) as validate() does.
void validate_shading(const Scene& scene);
// Also checks the objects' material references against scene.materials.
void validate_objects(const Scene& scene);

}  // namespace kdrt::detail
