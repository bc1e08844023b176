// The in-memory scene: what a scene file describes (FORMAT.md), built either by
// the JSON loader or programmatically through the add_* calls below.
//
// Object ids follow FORMAT.md: spheres first (in order), then the loose
// triangles, then the triangles of each mesh in order. Geometry is kept in
// double precision exactly as given; renderers derive their own working copies.
#pragma once

#include <kdrt/export.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace kdrt {

using MaterialId = std::uint32_t;

struct Camera {
    glm::dvec3 position{0.0, 0.0, -5.0};
    glm::dvec3 look_at{0.0, 0.0, 0.0};
    glm::dvec3 up{0.0, 1.0, 0.0};
    double fov_y = 45.0;  // vertical field of view in degrees, (0, 180)
};

struct RenderSettings {
    int width = 500;        // pixels, 1..16384
    int height = 500;       // pixels, 1..16384
    int max_depth = 15;     // camera ray = depth 1
    int samples = 1;        // camera rays per pixel
    glm::dvec3 background{0.0};
    glm::dvec3 ambient{0.0};
};

struct Material {
    std::string name;
    glm::dvec3 color{1.0};
    double diffuse = 1.0;     // kd
    double specular = 0.0;    // ks
    double shininess = 32.0;  // Phong exponent n > 0
    double reflect = 0.0;     // kr in [0, 1]
    double transmit = 0.0;    // kt in [0, 1]
    double ior = 1.5;         // inside index of refraction, used when transmit > 0
};

struct PointLight {
    glm::dvec3 position{0.0};
    glm::dvec3 color{1.0};
};

struct Sphere {
    glm::dvec3 center{0.0};
    double radius = 1.0;
    MaterialId material = 0;
};

inline constexpr std::uint32_t kNoNormal = std::numeric_limits<std::uint32_t>::max();

// One triangle of a mesh: indices into the mesh's shared arrays.
struct MeshTriangle {
    std::array<std::uint32_t, 3> v{};                              // into positions
    std::array<std::uint32_t, 3> n{kNoNormal, kNoNormal, kNoNormal};  // into normals, or kNoNormal
    MaterialId material = 0;
};

// A triangle mesh: shared vertex and normal arrays plus one index triple per
// triangle. Loose triangles of a scene file live in Scene::triangles, a mesh
// whose vertices are not shared.
struct Mesh {
    std::vector<glm::dvec3> positions;
    std::vector<glm::dvec3> normals;  // shading normals; may be empty
    std::vector<MeshTriangle> triangles;

    std::size_t size() const { return triangles.size(); }
};

// Objects added by one add_* call (or by consecutive add_sphere or
// add_triangle calls): a run of ids in Scene::added. Spheres and Triangles
// runs are one geometry per object (each add_sphere or add_triangle call);
// a Mesh (add_mesh) and a SphereSet (add_spheres) are one geometry.
struct AddedObjects {
    enum class Kind : std::uint8_t { Spheres, Triangles, Mesh, SphereSet };
    Kind kind = Kind::Spheres;
    std::uint32_t first = 0;  // Spheres, SphereSet: into spheres; Triangles: into triangles.triangles; Mesh: into meshes
    std::uint32_t count = 0;  // objects (Mesh: that mesh's triangles)
};

// Object ids. An object's id is what add_sphere / add_triangle / add_mesh
// returned, for good: hits, id maps and ray queries report it. The add_*
// calls record their order in `added`; the ids are positions in that order.
// Objects pushed into `spheres`, `triangles` or `meshes` directly (not
// through add_*) get the ids after the recorded ones, in FORMAT.md's order
// (spheres, loose triangles, meshes). A scene file is loaded in FORMAT.md's
// order, so its ids are FORMAT.md's. Removing objects that add_* recorded
// makes `added` refer to missing objects: clear it (or edit it) as well;
// a render refuses such a scene with kdrt::Error(InvalidScene).
//
// Geometry ids, as Embree's and Open3D's: each add_* call adds one geometry,
// numbered from 0 in call order (geometry_count() before the call), whose
// objects are its primitives 0, 1, ... in order (a mesh's triangles, the
// spheres of add_spheres; add_sphere and add_triangle add one). Objects not
// added through add_* (a loaded file, direct pushes) follow in FORMAT.md's
// order: each sphere and each loose triangle a geometry of its own, each mesh
// one. Ray queries report both (QueryHit::geometry and ::primitive).
//
// Materials: a scene without any may still have objects (ray queries need
// none): their material must be 0, and renders shade them with Material{}.
struct KDRT_API Scene {
    std::string name = "untitled";
    Camera camera;
    RenderSettings settings;
    std::vector<Material> materials;
    std::vector<PointLight> lights;
    std::vector<Sphere> spheres;
    Mesh triangles;             // the file's "triangles" entries, ids after the spheres
    std::vector<Mesh> meshes;   // the file's "meshes", ids after the loose triangles
    std::vector<AddedObjects> added;  // the add_* calls' order: the object ids (see above)

    // Programmatic construction. Each returns the id of what it added.
    MaterialId add_material(Material m);
    std::uint32_t add_light(const PointLight& light);
    std::uint32_t add_sphere(const glm::dvec3& center, double radius, MaterialId material);
    std::uint32_t add_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                               MaterialId material);
    std::uint32_t add_mesh(Mesh mesh);  // returns the object id of its first triangle; the others follow
    // Several spheres as one geometry; returns the object id of the first, the others follow.
    std::uint32_t add_spheres(const std::vector<Sphere>& spheres);

    // How many geometries the add_* calls have added: the next call's geometry id.
    std::uint32_t geometry_count() const;

    // Looks a material up by name; throws kdrt::Error if there is none.
    MaterialId material_id(const std::string& name) const;

    std::size_t triangle_count() const;
    std::size_t object_count() const { return spheres.size() + triangle_count(); }
};

// Checks every rule of FORMAT.md that does not depend on the file syntax:
// finite numbers, ranges, material references, index bounds, camera sanity.
// Throws kdrt::Error(InvalidScene) naming the offending element
// (e.g. "spheres[3].radius: must be > 0, got -1").
KDRT_API void validate(const Scene& scene);

}  // namespace kdrt
