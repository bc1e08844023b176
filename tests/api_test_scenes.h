// Scenes for the public-API tests ([api]): random spheres and triangles with
// a grid of quads sharing edges, placed away from the world origin so that
// the working frame's shift is exercised.
#pragma once

#include <kdrt/scene.h>

#include <random>

namespace kdrt_test {

inline kdrt::Scene api_scene(std::uint32_t seed, glm::dvec3 offset = {1000.0, -250.0, 40.0}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0), small(0.05, 0.6);
    kdrt::Scene s;
    s.camera.position = offset + glm::dvec3(0, 0, -12);
    s.camera.look_at = offset;
    s.settings.width = 48;
    s.settings.height = 32;
    auto m = s.add_material({});
    kdrt::Material mirror;
    mirror.reflect = 0.4;
    auto shiny = s.add_material(mirror);
    s.add_light({offset + glm::dvec3(3, 8, -6), {1, 1, 1}});
    for (int i = 0; i < 12; ++i) s.add_sphere(offset + glm::dvec3(u(rng), u(rng), u(rng)), small(rng), i % 3 ? m : shiny);
    for (int i = 0; i < 40; ++i) {
        const glm::dvec3 a = offset + glm::dvec3(u(rng), u(rng), u(rng));
        s.add_triangle(a, a + glm::dvec3(small(rng), small(rng), u(rng) * 0.2),
                       a + glm::dvec3(-small(rng), small(rng), small(rng)), m);
    }
    // Axis-aligned unit quads on a grid: shared edges and vertices on split planes.
    kdrt::Mesh grid;
    for (int y = -3; y <= 3; ++y)
        for (int x = -3; x <= 3; ++x) grid.positions.push_back(offset + glm::dvec3(x, y, 2.0));
    for (std::uint32_t y = 0; y < 6; ++y)
        for (std::uint32_t x = 0; x < 6; ++x) {
            const std::uint32_t a = y * 7 + x;
            grid.triangles.push_back({{a, a + 1, a + 8}, {kdrt::kNoNormal, kdrt::kNoNormal, kdrt::kNoNormal}, m});
            grid.triangles.push_back({{a, a + 8, a + 7}, {kdrt::kNoNormal, kdrt::kNoNormal, kdrt::kNoNormal}, m});
        }
    s.add_mesh(std::move(grid));
    return s;
}

}  // namespace kdrt_test
