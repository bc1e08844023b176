// A test mesh: a tessellated sheet of n x n quads over [0, 1]^2 in the z = 0
// plane, its vertices displaced in z by `wave` times a smooth wave, so that
// moving them (another `wave`) keeps the same triangles.
#pragma once

#include <kdrt/scene.h>

#include <cmath>
#include <cstdint>
#include <utility>

namespace kdrt_test {

inline void add_wavy_sheet(kdrt::Scene& s, int n, double wave, kdrt::MaterialId m) {
    kdrt::Mesh mesh;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x)
            mesh.positions.push_back({double(x) / n, double(y) / n, wave * std::sin(7.0 * x / n + 3.0 * y / n)});
    const auto at = [&](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
    constexpr auto none = kdrt::kNoNormal;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            mesh.triangles.push_back({{at(x, y), at(x + 1, y), at(x + 1, y + 1)}, {none, none, none}, m});
            mesh.triangles.push_back({{at(x, y), at(x + 1, y + 1), at(x, y + 1)}, {none, none, none}, m});
        }
    s.add_mesh(std::move(mesh));
}

}  // namespace kdrt_test
