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

// The geometries (scene.h) as runs of public ids: geometry g is the objects
// [first[g], first[g + 1]), the last one up to the object count (an empty
// mesh's geometry has none). Empty when every geometry is one object: then
// the geometry id is the object id. The scene's `added` must be valid
// (public_object_ids() does not throw for it).
std::vector<std::uint32_t> geometry_first_ids(const Scene& scene);

// Where geometry_first_ids() puts public object id `id`.
struct GeometryPrimitive {
    std::uint32_t geometry, primitive;
};
GeometryPrimitive geometry_primitive(const std::vector<std::uint32_t>& geometry_first, std::uint32_t id);

}  // namespace kdrt::detail
