#include "povray_export.h"

#include <kdrt/error.h>

#include <glm/geometric.hpp>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace kdrt::bench {

namespace {

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string vec(const glm::dvec3& v) {
    std::string s(1, '<');
    s.append(num(v.x)).append(", ").append(num(v.y)).append(", ").append(num(v.z)).append(">");
    return s;
}

std::string identifier(std::size_t index, const std::string& name) {
    std::string id(1, 'M');
    id.append(std::to_string(index)).append("_");
    for (char c : name) id += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return id;
}

void write_material(std::ostringstream& o, const std::string& id, const Material& m) {
    o << "#declare " << id << " = material {\n  texture {\n    pigment { color ";
    if (m.transmit > 0.0) o << "rgbt <" << num(m.color.x) << ", " << num(m.color.y) << ", " << num(m.color.z) << ", " << num(m.transmit) << ">";
    else o << "rgb " << vec(m.color);
    o << " }\n    finish { ambient " << num(m.diffuse) << " diffuse " << num(m.diffuse);
    if (m.specular > 0.0) o << " phong " << num(m.specular) << " phong_size " << num(m.shininess);
    if (m.reflect > 0.0) o << " reflection { " << num(m.reflect) << " }";
    o << " }\n  }\n";
    if (m.transmit > 0.0) o << "  interior { ior " << num(m.ior) << " }\n";
    o << "}\n";
}

bool degenerate(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    return glm::length(glm::cross(b - a, c - a)) == 0.0;
}

// One POV-Ray mesh per (kdrt mesh, material): meshes are POV-Ray's compact,
// internally bounded triangle container.
void write_mesh(std::ostringstream& o, const Mesh& mesh, const std::vector<std::string>& ids) {
    std::map<MaterialId, std::vector<const MeshTriangle*>> by_material;
    for (const MeshTriangle& t : mesh.triangles) by_material[t.material].push_back(&t);
    for (const auto& [material, tris] : by_material) {
        o << "mesh {\n";
        for (const MeshTriangle* t : tris) {
            const glm::dvec3 &a = mesh.positions[t->v[0]], &b = mesh.positions[t->v[1]], &c = mesh.positions[t->v[2]];
            if (degenerate(a, b, c)) continue;  // never hit (FORMAT.md); POV-Ray would warn
            const bool smooth = t->n[0] != kNoNormal && t->n[1] != kNoNormal && t->n[2] != kNoNormal;
            if (smooth)
                o << "  smooth_triangle { " << vec(a) << ", " << vec(glm::normalize(mesh.normals[t->n[0]])) << ", "
                  << vec(b) << ", " << vec(glm::normalize(mesh.normals[t->n[1]])) << ", " << vec(c) << ", "
                  << vec(glm::normalize(mesh.normals[t->n[2]])) << " }\n";
            else
                o << "  triangle { " << vec(a) << ", " << vec(b) << ", " << vec(c) << " }\n";
        }
        o << "  material { " << ids[material] << " }\n}\n";
    }
}

}  // namespace

std::string to_povray(const Scene& scene, int width, int height) {
    validate(scene);
    const int W = width > 0 ? width : scene.settings.width;
    const int H = height > 0 ? height : scene.settings.height;
    const double aspect = static_cast<double>(W) / H;
    const double pi = 3.14159265358979323846;
    const double h_angle = 2.0 * std::atan(aspect * std::tan(scene.camera.fov_y * pi / 360.0)) * 180.0 / pi;
    const RenderSettings& st = scene.settings;

    std::ostringstream o;
    o << "// " << scene.name << ", converted from a kdrt scene by kdrt-bench povray (" << W << "x" << H << ").\n"
      << "// Render: povray +W" << W << " +H" << H << " -D -A +FN File_Gamma=1.0 +I<this file>\n"
      << "#version 3.7;\n"
      << "global_settings { assumed_gamma 1.0 max_trace_level " << st.max_depth << " ambient_light rgb "
      << vec(st.ambient) << " }\n"
      << "background { color rgb " << vec(st.background) << " }\n"
      // POV-Ray is left-handed; `right -x` gives FORMAT.md's right-handed camera (right = forward x up).
      << "camera {\n  perspective\n  location " << vec(scene.camera.position) << "\n  sky " << vec(scene.camera.up)
      << "\n  up y\n  right -x*" << num(aspect) << "\n  angle " << num(h_angle) << "\n  look_at "
      << vec(scene.camera.look_at) << "\n}\n";
    for (const PointLight& l : scene.lights) o << "light_source { " << vec(l.position) << " color rgb " << vec(l.color) << " }\n";

    std::vector<std::string> ids;
    for (std::size_t i = 0; i < scene.materials.size(); ++i) {
        ids.push_back(identifier(i, scene.materials[i].name));
        write_material(o, ids.back(), scene.materials[i]);
    }
    for (const Sphere& s : scene.spheres)
        o << "sphere { " << vec(s.center) << ", " << num(s.radius) << " material { " << ids[s.material] << " } }\n";
    if (!scene.triangles.triangles.empty()) write_mesh(o, scene.triangles, ids);
    for (const Mesh& m : scene.meshes) write_mesh(o, m, ids);
    return o.str();
}

void write_povray(const Scene& scene, const std::filesystem::path& path, int width, int height) {
    std::ofstream file(path);
    file << to_povray(scene, width, height);
    if (!file) throw Error(ErrorCode::Io, path.string() + ": cannot write");
}

}  // namespace kdrt::bench
