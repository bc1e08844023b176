#include "common/parallel_chunks.h"
#include "common/printable_text.h"
#include "scene/scene_validation.h"

#include <kdrt/error.h>
#include <kdrt/scene.h>
#include <kdrt/layout.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace kdrt {

const char* to_string(ErrorCode code) {
    switch (code) {
        case ErrorCode::InvalidScene: return "invalid scene";
        case ErrorCode::Io: return "I/O error";
        case ErrorCode::InvalidArgument: return "invalid argument";
        case ErrorCode::CorruptTree: return "corrupt kd-tree";
        case ErrorCode::Device: return "device error";
        case ErrorCode::Unsupported: return "unsupported";
        case ErrorCode::Cancelled: return "cancelled";
        case ErrorCode::ResourceLimit: return "resource limit";
    }
    return "error";
}

MaterialId Scene::add_material(Material m) {
    if (m.name.empty()) m.name = "material" + std::to_string(materials.size());
    materials.push_back(std::move(m));
    return static_cast<MaterialId>(materials.size() - 1);
}

std::uint32_t Scene::add_light(const PointLight& light) {
    lights.push_back(light);
    return static_cast<std::uint32_t>(lights.size() - 1);
}

namespace {

// Records objects added by one call; a run of the same kind continues the last one.
std::uint32_t record(std::vector<AddedObjects>& added, AddedObjects::Kind kind, std::size_t first,
                     std::size_t count) {
    std::uint64_t id = 0;
    for (const AddedObjects& a : added) id += a.count;
    if (id + count > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::InvalidScene, "more than 2^32 - 1 objects");
    AddedObjects* last = added.empty() ? nullptr : &added.back();
    const bool per_object = kind == AddedObjects::Kind::Spheres || kind == AddedObjects::Kind::Triangles;
    if (last && per_object && last->kind == kind && last->first + last->count == first)
        last->count += static_cast<std::uint32_t>(count);
    else
        added.push_back({kind, static_cast<std::uint32_t>(first), static_cast<std::uint32_t>(count)});
    return static_cast<std::uint32_t>(id);
}

}  // namespace

std::uint32_t Scene::add_sphere(const glm::dvec3& center, double radius, MaterialId material) {
    spheres.push_back({center, radius, material});
    return record(added, AddedObjects::Kind::Spheres, spheres.size() - 1, 1);
}

std::uint32_t Scene::add_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                  MaterialId material) {
    auto base = static_cast<std::uint32_t>(triangles.positions.size());
    triangles.positions.insert(triangles.positions.end(), {a, b, c});
    MeshTriangle t;
    t.v = {base, base + 1, base + 2};
    t.material = material;
    triangles.triangles.push_back(t);
    return record(added, AddedObjects::Kind::Triangles, triangles.size() - 1, 1);
}

std::uint32_t Scene::add_mesh(Mesh mesh) {
    const std::size_t count = mesh.size();
    meshes.push_back(std::move(mesh));
    return record(added, AddedObjects::Kind::Mesh, meshes.size() - 1, count);
}

std::uint32_t Scene::add_spheres(const std::vector<Sphere>& more) {
    const std::size_t first = spheres.size();
    spheres.insert(spheres.end(), more.begin(), more.end());
    return record(added, AddedObjects::Kind::SphereSet, first, more.size());
}

std::uint32_t Scene::geometry_count() const {
    std::uint64_t n = 0;
    for (const AddedObjects& a : added)
        n += a.kind == AddedObjects::Kind::Spheres || a.kind == AddedObjects::Kind::Triangles ? a.count : 1;
    return static_cast<std::uint32_t>(n);
}

MaterialId Scene::material_id(const std::string& material_name) const {
    for (std::size_t i = 0; i < materials.size(); ++i)
        if (materials[i].name == material_name) return static_cast<MaterialId>(i);
    throw Error(ErrorCode::InvalidArgument, "no material named '" + detail::printable(material_name) + "'");
}

std::size_t Scene::triangle_count() const {
    std::size_t n = triangles.size();
    for (const Mesh& m : meshes) n += m.size();
    return n;
}

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& what) {
    throw Error(ErrorCode::InvalidScene, where + ": " + what);
}

std::string str(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_vec(const std::string& where, const glm::dvec3& v) {
    if (!finite(v)) fail(where, "must be 3 finite numbers");
}

void check_number(const std::string& where, double v) {
    if (!std::isfinite(v)) fail(where, "must be a finite number, got " + str(v));
}

void check_range(const std::string& where, double v, double lo, double hi) {
    check_number(where, v);
    if (v < lo || v > hi)
        fail(where, "must be in [" + str(lo) + ", " + str(hi) + "], got " + str(v));
}

void check_positive(const std::string& where, double v) {
    check_number(where, v);
    if (!(v > 0.0)) fail(where, "must be > 0, got " + str(v));
}

// Places are spelled out only on failure: a mesh has millions of elements.
// Each array is scanned in parallel for its first fault, which the serial
// checks below then name: the same message as a scan in order.
void check_mesh(const std::string& where, const Mesh& mesh, std::size_t material_count) {
    const std::size_t p = detail::first_index_where(mesh.positions.size(),
                                                    [&](std::size_t i) { return !finite(mesh.positions[i]); });
    if (p < mesh.positions.size()) check_vec(where + ".positions[" + std::to_string(p) + "]", mesh.positions[p]);
    // A shading normal is normalised where it is used: zero length would give NaN.
    const std::size_t n = detail::first_index_where(mesh.normals.size(), [&](std::size_t i) {
        return !finite(mesh.normals[i]) || !(glm::length(mesh.normals[i]) > 0.0);
    });
    if (n < mesh.normals.size()) {
        const std::string at = where + ".normals[" + std::to_string(n) + "]";
        check_vec(at, mesh.normals[n]);
        fail(at, "must have a non-zero length");
    }
    const std::size_t t = detail::first_index_where(mesh.triangles.size(), [&](std::size_t i) {
        const MeshTriangle& tri = mesh.triangles[i];
        bool bad = tri.material >= material_count;
        for (std::uint32_t v : tri.v) bad |= v >= mesh.positions.size();
        for (std::uint32_t k : tri.n) bad |= k != kNoNormal && k >= mesh.normals.size();
        return bad;
    });
    if (t == mesh.triangles.size()) return;
    const MeshTriangle& tri = mesh.triangles[t];
    const std::string at = where + "[" + std::to_string(t) + "]";
    for (std::uint32_t v : tri.v)
        if (v >= mesh.positions.size()) fail(at, "vertex index " + std::to_string(v) + " out of range");
    for (std::uint32_t k : tri.n)
        if (k != kNoNormal && k >= mesh.normals.size())
            fail(at, "normal index " + std::to_string(k) + " out of range");
    fail(at + ".material", "undefined material");
}

}  // namespace

void detail::validate_shading(const Scene& scene) {
    const Camera& cam = scene.camera;
    check_vec("camera.position", cam.position);
    check_vec("camera.look_at", cam.look_at);
    check_vec("camera.up", cam.up);
    // Lengths are taken of vectors scaled to a largest component of 1, so that
    // huge or tiny (but finite) coordinates neither overflow nor underflow
    // into a wrong diagnosis.
    auto largest = [](const glm::dvec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); };
    const glm::dvec3 forward = cam.look_at - cam.position;
    const double reach = largest(forward);
    if (!std::isfinite(reach) || reach > 1e30)
        fail("camera.look_at", "is " + str(reach) + " from camera.position, more than the float range kdrt works in (1e30)");
    if (!(reach > 0.0)) fail("camera.look_at", "must differ from camera.position");
    if (!(largest(cam.up) > 0.0)) fail("camera.up", "must not be zero");
    const glm::dvec3 side = glm::cross(glm::normalize(forward / reach), glm::normalize(cam.up / largest(cam.up)));
    if (!(glm::length(side) > 1e-12)) fail("camera.up", "must not be parallel to the view direction");
    check_number("camera.fov_y", cam.fov_y);
    if (!(cam.fov_y > 0.0 && cam.fov_y < 180.0))
        fail("camera.fov_y", "must be in (0, 180), got " + str(cam.fov_y));

    const RenderSettings& s = scene.settings;
    if (s.width < 1 || s.width > 16384) fail("settings.width", "must be in [1, 16384], got " + std::to_string(s.width));
    if (s.height < 1 || s.height > 16384) fail("settings.height", "must be in [1, 16384], got " + std::to_string(s.height));
    if (s.max_depth < 1 || s.max_depth > KDRT_MAX_RAY_DEPTH)
        fail("settings.max_depth", "must be in [1, " + std::to_string(KDRT_MAX_RAY_DEPTH) + "], got " + std::to_string(s.max_depth));
    if (s.samples < 1) fail("settings.samples", "must be >= 1, got " + std::to_string(s.samples));
    check_vec("settings.background", s.background);
    check_vec("settings.ambient", s.ambient);

    for (std::size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        std::string at = "materials." + detail::printable(m.name);
        check_vec(at + ".color", m.color);
        check_number(at + ".diffuse", m.diffuse);
        check_number(at + ".specular", m.specular);
        check_positive(at + ".shininess", m.shininess);
        check_range(at + ".reflect", m.reflect, 0.0, 1.0);
        check_range(at + ".transmit", m.transmit, 0.0, 1.0);
        check_positive(at + ".ior", m.ior);
    }
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        std::string at = "lights[" + std::to_string(i) + "]";
        check_vec(at + ".position", scene.lights[i].position);
        check_vec(at + ".color", scene.lights[i].color);
    }
}

void detail::validate_objects(const Scene& scene) {
    // Without materials, material 0 is the default one (scene.h).
    const std::size_t materials = std::max<std::size_t>(scene.materials.size(), 1);
    for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
        const Sphere& sp = scene.spheres[i];
        std::string at = "spheres[" + std::to_string(i) + "]";
        check_vec(at + ".center", sp.center);
        check_positive(at + ".radius", sp.radius);
        if (sp.material >= materials) fail(at + ".material", "undefined material");
    }
    check_mesh("triangles", scene.triangles, materials);
    for (std::size_t i = 0; i < scene.meshes.size(); ++i)
        check_mesh("meshes[" + std::to_string(i) + "]", scene.meshes[i], materials);
    if (scene.object_count() >= (std::size_t{1} << 30))
        fail("scene", "too many objects (" + std::to_string(scene.object_count()) + "), at most 2^30 - 1");
}

void validate(const Scene& scene) {
    detail::validate_shading(scene);
    detail::validate_objects(scene);
}

}  // namespace kdrt
