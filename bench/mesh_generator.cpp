#include "mesh_generator.h"

#include <kdrt/error.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

namespace kdrt::bench {

namespace {

// Two triangles per quad of a rows x cols grid of quads; vertex(i, j) is the
// index of grid point (i, j), i in [0, rows], j in [0, cols] (a closed surface
// wraps around there).
template <class VertexIndex>
void add_quad_grid(Mesh& mesh, std::uint32_t rows, std::uint32_t cols, VertexIndex vertex, MaterialId material) {
    mesh.triangles.reserve(mesh.triangles.size() + 2ull * rows * cols);
    for (std::uint32_t i = 0; i < rows; ++i)
        for (std::uint32_t j = 0; j < cols; ++j) {
            MeshTriangle a, b;
            a.v = {vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1)};
            b.v = {vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1)};
            a.material = b.material = material;
            mesh.triangles.push_back(a);
            mesh.triangles.push_back(b);
        }
}

}  // namespace

Scene make_torus_scene(std::size_t triangles) {
    const auto nv = static_cast<std::uint32_t>(std::max(3.0, std::round(std::sqrt(static_cast<double>(triangles) / 4.0))));
    const std::uint32_t nu = 2 * nv;
    const double R = 1.0, r = 0.35, two_pi = 6.283185307179586;
    Scene scene;
    scene.name = "torus-" + std::to_string(2ull * nu * nv);
    scene.camera.position = {0.0, 2.2, -2.6};
    scene.camera.look_at = {0.0, 0.0, 0.0};
    scene.camera.fov_y = 45.0;
    scene.settings.ambient = glm::dvec3(0.1);
    const MaterialId m = scene.add_material({.name = "torus", .color = {0.8, 0.6, 0.3}, .specular = 0.3});
    scene.add_light({{2.0, 4.0, -3.0}, {1.0, 1.0, 1.0}});
    Mesh mesh;
    mesh.positions.reserve(static_cast<std::size_t>(nu) * nv);
    for (std::uint32_t i = 0; i < nu; ++i) {
        const double u = two_pi * i / nu;
        for (std::uint32_t j = 0; j < nv; ++j) {
            const double v = two_pi * j / nv;
            mesh.positions.push_back({(R + r * std::cos(v)) * std::cos(u), r * std::sin(v), (R + r * std::cos(v)) * std::sin(u)});
        }
    }
    add_quad_grid(mesh, nu, nv, [&](std::uint32_t i, std::uint32_t j) { return (i % nu) * nv + (j % nv); }, m);
    scene.add_mesh(std::move(mesh));
    return scene;
}

namespace {

// Deterministic noise in [-1, 1] from a grid point (a 32-bit integer hash, Wellons' "lowbias32").
double hashed_noise(std::uint32_t i, std::uint32_t j) {
    std::uint32_t x = i * 0x9E3779B1u ^ (j + 0x7F4A7C15u);
    x ^= x >> 16;
    x *= 0x7FEB352Du;
    x ^= x >> 15;
    x *= 0x846CA68Bu;
    x ^= x >> 16;
    return static_cast<double>(x) / 2147483647.5 - 1.0;
}

}  // namespace

Scene make_heightfield_scene(std::uint32_t points) {
    if (points < 2) throw Error(ErrorCode::InvalidArgument, "a heightfield needs at least 2x2 grid points");
    const std::uint32_t n = points;
    Scene scene;
    scene.name = "heightfield-" + std::to_string(2ull * (n - 1) * (n - 1));
    scene.camera.position = {0.0, 1.1, -1.9};
    scene.camera.look_at = {0.0, 0.0, 0.0};
    scene.camera.fov_y = 50.0;
    scene.settings.ambient = glm::dvec3(0.1);
    const MaterialId m = scene.add_material({.name = "ground", .color = {0.5, 0.7, 0.4}});
    scene.add_light({{1.0, 3.0, -2.0}, {1.0, 1.0, 1.0}});
    Mesh mesh;
    mesh.positions.reserve(static_cast<std::size_t>(n) * n);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t j = 0; j < n; ++j) {
            const double x = -1.0 + 2.0 * i / (n - 1), z = -1.0 + 2.0 * j / (n - 1);
            const double h = 0.15 * std::sin(3.0 * x) * std::cos(2.0 * z) + 0.05 * std::sin(11.0 * x + 7.0 * z) +
                             0.004 * hashed_noise(i, j);
            mesh.positions.push_back({x, h, z});
        }
    add_quad_grid(mesh, n - 1, n - 1, [&](std::uint32_t i, std::uint32_t j) { return i * n + j; }, m);
    scene.add_mesh(std::move(mesh));
    return scene;
}

Scene make_layers_scene(std::uint32_t layers) {
    constexpr std::uint32_t kQuads = 64, kPoints = kQuads + 1;
    Scene scene;
    scene.name = "layers-" + std::to_string(2ull * kQuads * kQuads * layers);
    const double top = 0.02 * (layers - 1);
    scene.camera.position = {-2.2, 0.5 * top + 0.08, -0.3};  // just above the stack's middle, looking across it
    scene.camera.look_at = {0.0, 0.5 * top, 0.0};
    scene.camera.fov_y = 40.0;
    scene.settings.ambient = glm::dvec3(0.1);
    const MaterialId m = scene.add_material({.name = "sheet", .color = {0.6, 0.6, 0.8}});
    scene.add_light({{-1.0, top + 2.0, -2.0}, {1.0, 1.0, 1.0}});
    Mesh mesh;
    mesh.positions.reserve(static_cast<std::size_t>(kPoints) * kPoints * layers);
    for (std::uint32_t l = 0; l < layers; ++l) {
        const auto base = static_cast<std::uint32_t>(mesh.positions.size());
        for (std::uint32_t i = 0; i < kPoints; ++i)
            for (std::uint32_t j = 0; j < kPoints; ++j) {
                const double x = -1.0 + 2.0 * i / kQuads, z = -1.0 + 2.0 * j / kQuads;
                const double y = 0.02 * l + 0.006 * std::sin(5.0 * x + 1.3 * l) * std::cos(4.0 * z - 0.7 * l);
                mesh.positions.push_back({x, y, z});
            }
        add_quad_grid(mesh, kQuads, kQuads, [&](std::uint32_t i, std::uint32_t j) { return base + i * kPoints + j; }, m);
    }
    scene.add_mesh(std::move(mesh));
    return scene;
}

std::size_t parse_count(const std::string& text) {
    try {
        std::size_t pos = 0;
        const double v = std::stod(text, &pos);
        double scale = 1.0;
        const std::string suffix = text.substr(pos);
        if (suffix == "k" || suffix == "K") scale = 1e3;
        else if (suffix == "M" || suffix == "m") scale = 1e6;
        else if (!suffix.empty()) throw std::invalid_argument("suffix");
        if (!(v > 0.0)) throw std::invalid_argument("range");
        return static_cast<std::size_t>(std::llround(v * scale));
    } catch (const std::exception&) {
        throw Error(ErrorCode::InvalidArgument, "'" + text + "': expected a count such as 100k or 4M");
    }
}

Scene make_generated_scene(const std::string& spec) {
    const auto colon = spec.find(':');
    const std::string kind = spec.substr(0, colon), size = colon == std::string::npos ? "" : spec.substr(colon + 1);
    if (kind == "torus") return make_torus_scene(parse_count(size.empty() ? "100k" : size));
    if (kind == "heightfield") {
        const std::size_t n = parse_count(size.empty() ? "1001" : size);
        if (n < 2 || n > 20000) throw Error(ErrorCode::InvalidArgument, "'" + spec + "': 2 to 20000 grid points per side");
        return make_heightfield_scene(static_cast<std::uint32_t>(n));
    }
    if (kind == "layers") {
        const std::size_t n = parse_count(size.empty() ? "32" : size);
        if (n > 1024) throw Error(ErrorCode::InvalidArgument, "'" + spec + "': 1 to 1024 layers");
        return make_layers_scene(static_cast<std::uint32_t>(n));
    }
    throw Error(ErrorCode::InvalidArgument, "'" + spec + "': expected torus:COUNT, heightfield:POINTS or layers:COUNT");
}

std::string write_scene_files(const Scene& scene, const std::string& dir) {
    if (scene.meshes.size() != 1 || !scene.spheres.empty() || scene.triangles.size() != 0)
        throw Error(ErrorCode::InvalidArgument, "write_scene_files writes scenes of one mesh");
    std::filesystem::create_directories(dir);
    const std::filesystem::path obj = std::filesystem::path(dir) / (scene.name + ".obj");
    const std::filesystem::path json = std::filesystem::path(dir) / (scene.name + ".json");
    {
        // "%.9g" keeps every double that came from a float exactly; C stdio for speed on millions of lines.
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(obj.c_str(), "w"), std::fclose);
        if (!f) throw Error(ErrorCode::Io, obj.string() + ": cannot write");
        const Mesh& m = scene.meshes[0];
        for (const glm::dvec3& p : m.positions) std::fprintf(f.get(), "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
        for (const MeshTriangle& t : m.triangles) std::fprintf(f.get(), "f %u %u %u\n", t.v[0] + 1, t.v[1] + 1, t.v[2] + 1);
        if (std::ferror(f.get())) throw Error(ErrorCode::Io, obj.string() + ": write failed");
    }
    auto vec = [](const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
    nlohmann::ordered_json j;
    j["format"] = "kdrt-scene/1";
    j["camera"] = {{"position", vec(scene.camera.position)}, {"look_at", vec(scene.camera.look_at)},
                   {"up", vec(scene.camera.up)}, {"fov_y", scene.camera.fov_y}};
    j["settings"] = {{"width", scene.settings.width}, {"height", scene.settings.height},
                     {"max_depth", scene.settings.max_depth}, {"background", vec(scene.settings.background)},
                     {"ambient", vec(scene.settings.ambient)}};
    for (const Material& m : scene.materials)
        j["materials"][m.name] = {{"color", vec(m.color)}, {"diffuse", m.diffuse}, {"specular", m.specular},
                                  {"shininess", m.shininess}, {"reflect", m.reflect}, {"transmit", m.transmit},
                                  {"ior", m.ior}};
    for (const PointLight& l : scene.lights) j["lights"].push_back({{"position", vec(l.position)}, {"color", vec(l.color)}});
    j["meshes"] = nlohmann::json::array(
        {{{"obj", obj.filename().string()}, {"material", scene.materials.at(scene.meshes[0].triangles.at(0).material).name}}});
    std::ofstream(json) << j.dump(2) << "\n";
    return json.string();
}

}  // namespace kdrt::bench
