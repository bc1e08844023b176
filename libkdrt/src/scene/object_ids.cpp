#include "scene/object_ids.h"

#include <kdrt/error.h>

#include <algorithm>
#include <string>

namespace kdrt::detail {

std::vector<std::uint32_t> public_object_ids(const Scene& scene) {
    if (scene.added.empty()) return {};
    const std::size_t spheres = scene.spheres.size(), loose = scene.triangles.size();
    std::vector<std::size_t> mesh_first(scene.meshes.size());
    std::size_t objects = spheres + loose;
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        mesh_first[m] = objects;
        objects += scene.meshes[m].size();
    }
    constexpr std::uint32_t kUnset = 0xFFFFFFFFu;
    std::vector<std::uint32_t> ids(objects, kUnset);
    std::uint32_t next = 0;
    for (std::size_t r = 0; r < scene.added.size(); ++r) {
        const AddedObjects& a = scene.added[r];
        const std::string where = "scene '" + scene.name + "': added[" + std::to_string(r) + "]";
        std::size_t first = 0, available = 0;
        switch (a.kind) {
            case AddedObjects::Kind::Spheres:
            case AddedObjects::Kind::SphereSet: first = a.first; available = spheres; break;
            case AddedObjects::Kind::Triangles: first = spheres + a.first; available = loose; break;
            case AddedObjects::Kind::Mesh:
                if (a.first >= scene.meshes.size() || a.count != scene.meshes[a.first].size())
                    throw Error(ErrorCode::InvalidScene, where + ": names mesh " + std::to_string(a.first) + " of " +
                                                             std::to_string(a.count) +
                                                             " triangles, which the scene no longer has");
                first = mesh_first[a.first];
                available = a.count;
                break;
        }
        if (a.kind != AddedObjects::Kind::Mesh && std::size_t{a.first} + a.count > available)
            throw Error(ErrorCode::InvalidScene, where + ": names objects " + std::to_string(a.first) + ".." +
                                                     std::to_string(std::size_t{a.first} + a.count) + " of " +
                                                     std::to_string(available) +
                                                     " (objects added by add_* were removed; clear Scene::added)");
        for (std::size_t i = first; i < first + a.count; ++i) {
            if (ids[i] != kUnset)
                throw Error(ErrorCode::InvalidScene, where + ": names an object added before");
            ids[i] = next++;
        }
    }
    bool identity = true;
    for (std::size_t i = 0; i < objects; ++i) {
        if (ids[i] == kUnset) ids[i] = next++;
        identity = identity && ids[i] == i;
    }
    if (identity) ids.clear();
    return ids;
}

std::vector<std::uint32_t> geometry_first_ids(const Scene& scene) {
    std::vector<std::uint32_t> first;
    std::uint32_t next = 0;  // public ids are handed out in the order of the geometries
    bool per_object = true;
    auto add = [&](std::uint32_t count, bool one_geometry) {
        if (one_geometry) {
            per_object = per_object && count == 1;
            first.push_back(next);
        } else {
            for (std::uint32_t i = 0; i < count; ++i) first.push_back(next + i);
        }
        next += count;
    };
    // Which internal objects `added` covers: the rest follow, in FORMAT.md's order.
    std::vector<bool> sphere_added(scene.spheres.size()), loose_added(scene.triangles.size()),
        mesh_added(scene.meshes.size());
    for (const AddedObjects& a : scene.added) {
        switch (a.kind) {
            case AddedObjects::Kind::Spheres:
            case AddedObjects::Kind::SphereSet:
                std::fill_n(sphere_added.begin() + a.first, a.count, true);
                break;
            case AddedObjects::Kind::Triangles: std::fill_n(loose_added.begin() + a.first, a.count, true); break;
            case AddedObjects::Kind::Mesh: mesh_added[a.first] = true; break;
        }
        add(a.count, a.kind == AddedObjects::Kind::Mesh || a.kind == AddedObjects::Kind::SphereSet);
    }
    for (bool added : sphere_added)
        if (!added) add(1, false);
    for (bool added : loose_added)
        if (!added) add(1, false);
    for (std::size_t m = 0; m < scene.meshes.size(); ++m)
        if (!mesh_added[m]) add(static_cast<std::uint32_t>(scene.meshes[m].size()), true);
    if (per_object) first.clear();
    return first;
}

GeometryPrimitive geometry_primitive(const std::vector<std::uint32_t>& geometry_first, std::uint32_t id) {
    if (geometry_first.empty()) return {id, 0};
    // The last geometry starting at or before `id` (empty geometries before it start there too).
    const auto it = std::upper_bound(geometry_first.begin(), geometry_first.end(), id) - 1;
    return {static_cast<std::uint32_t>(it - geometry_first.begin()), id - *it};
}

}  // namespace kdrt::detail
