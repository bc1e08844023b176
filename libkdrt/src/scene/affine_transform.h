// The one check of a mesh transform (FORMAT.md: a 4x4 row-major affine
// matrix), shared by the scene loader and load_obj_mesh.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <string>

namespace kdrt::detail {

// Empty when m is a usable transform, else what is wrong with it: singular
// (determinant 0), or ill-conditioned: a determinant tiny relative to the
// rows' lengths (its Hadamard bound), so the test does not depend on the
// scene's scale.
inline std::string affine_transform_problem(const std::array<double, 16>& m) {
    for (double v : m)
        if (!std::isfinite(v)) return "not finite";
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) return "not affine: the last row must be 0 0 0 1";
    const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                       m[2] * (m[4] * m[9] - m[5] * m[8]);
    const double r0 = std::hypot(m[0], m[1], m[2]), r1 = std::hypot(m[4], m[5], m[6]), r2 = std::hypot(m[8], m[9], m[10]);
    char text[160];
    if (det == 0.0 || !(r0 > 0.0 && r1 > 0.0 && r2 > 0.0)) return "singular matrix (determinant 0)";
    // |det| / (r0 r1 r2) is the volume of the rows scaled to unit length:
    // near 0 the rows are nearly parallel, however large det is (a strong shear).
    if (!(std::abs(det) / r0 / r1 / r2 > 1e-12)) {
        std::snprintf(text, sizeof text,
                      "ill-conditioned matrix: its rows are nearly parallel (determinant %g, row lengths %g, %g, %g)",
                      det, r0, r1, r2);
        return text;
    }
    return {};
}

}  // namespace kdrt::detail
