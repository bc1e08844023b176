#include "scene/geometry_digest.h"

#include "common/xxh3.h"

#include <array>
#include <cstring>
#include <type_traits>
#include <vector>

namespace kdrt::detail {

namespace {

// Arrays hashed as raw bytes must have no padding (padding bytes are not
// part of the value and may differ between equal elements).
static_assert(sizeof(glm::dvec3) == 3 * sizeof(double));
static_assert(std::has_unique_object_representations_v<MeshTriangle>);

void add_count(Xxh3x128& h, std::size_t n) {
    const std::uint64_t v = n;
    h.update(&v, sizeof v);
}

template <class T>
void add_array(Xxh3x128& h, const std::vector<T>& v) {
    add_count(h, v.size());
    h.update(v.data(), v.size() * sizeof(T));
}

void add_mesh(Xxh3x128& h, const Mesh& m) {
    add_array(h, m.positions);
    add_array(h, m.normals);
    add_array(h, m.triangles);
}

}  // namespace

GeometryDigest geometry_digest(const Scene& scene) {
    Xxh3x128 h;
    // Spheres and Scene::added have padding: their fields go through a buffer.
    add_count(h, scene.spheres.size());
    std::vector<unsigned char> buffer;
    constexpr std::size_t kSphereBytes = 4 * sizeof(double) + sizeof(MaterialId);
    buffer.reserve(4096 * kSphereBytes);
    for (const Sphere& s : scene.spheres) {
        const std::size_t at = buffer.size();
        buffer.resize(at + kSphereBytes);
        const double d[4] = {s.center.x, s.center.y, s.center.z, s.radius};
        std::memcpy(buffer.data() + at, d, sizeof d);
        std::memcpy(buffer.data() + at + sizeof d, &s.material, sizeof s.material);
        if (buffer.size() == buffer.capacity()) {
            h.update(buffer.data(), buffer.size());
            buffer.clear();
        }
    }
    h.update(buffer.data(), buffer.size());
    add_mesh(h, scene.triangles);
    add_count(h, scene.meshes.size());
    for (const Mesh& m : scene.meshes) add_mesh(h, m);
    add_count(h, scene.added.size());
    for (const AddedObjects& a : scene.added) {
        const std::array<std::uint32_t, 3> fields{static_cast<std::uint32_t>(a.kind), a.first, a.count};
        h.update(fields.data(), sizeof fields);
    }
    const XXH128_hash_t d = h.digest();
    return {d.low64, d.high64};
}

}  // namespace kdrt::detail
