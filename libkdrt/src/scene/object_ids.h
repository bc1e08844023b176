// Public object ids (Scene::added, see scene.h) against the internal ones
// (FORMAT.md's order: spheres, loose triangles, meshes), which geometry,
// trees and kernels use.
#pragma once

#include <kdrt/scene.h>

#include <cstdint>
#include <vector>

namespace kdrt::detail {

// internal id -> public id; empty when they agree (the common case: objects
// added in FORMAT.md's order, or not through add_*). Throws
// kdrt::Error(InvalidScene) when Scene::added names objects the scene does
// not have or names one twice.
std::vector<std::uint32_t> public_object_ids(const Scene& scene);

}  // namespace kdrt::detail
