// A digest of a Scene's objects exactly as given: what CommittedScene::update()
// compares to learn, without preparing the scene again, whether its geometry
// changed.
//
// Scene is a plain struct whose vectors callers may change in place, so no
// version counter can tell; a digest of the input can. It covers everything
// prepare_scene() makes geometry, trees, device buffers and object ids from:
// spheres, the loose triangles and meshes (positions, normals, index triples
// with their materials, including unreferenced entries) and Scene::added,
// with every count. A single XXH3-128 pass over the raw arrays at memory
// speed (40 MB, some 2-3 ms, for a 1M-triangle mesh) against 80-150 ms for
// preparing it. Bitwise, not by value: -0.0 against 0.0 reads as a change,
// which only costs a preparation.
#pragma once

#include <kdrt/scene.h>

#include <cstdint>

namespace kdrt::detail {

struct GeometryDigest {
    std::uint64_t low = 0, high = 0;
    friend bool operator==(const GeometryDigest&, const GeometryDigest&) = default;
};

GeometryDigest geometry_digest(const Scene& scene);

}  // namespace kdrt::detail
