// The one check of a mesh transform (FORMAT.md: a 4x4 row-major affine
// matrix), shared by the scene loader and load_obj_mesh.
#pragma once

#include <array>
#include <cmath>
#include <string>

namespace kdrt::detail {

// Empty when m is a usable transform, else what is wrong with it. Singular
// means a determinant tiny relative to the rows' lengths (its Hadamard bound),
// so the test does not depend on the scene's scale.
inline std::string affine_transform_problem(const std::array<double, 16>& m) {
    for (double v : m)
        if (!std::isfinite(v)) return "not finite";
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) return "not affine: the last row must be 0 0 0 1";
    const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                       m[2] * (m[4] * m[9] - m[5] * m[8]);
    const double bound = std::hypot(m[0], m[1], m[2]) * std::hypot(m[4], m[5], m[6]) * std::hypot(m[8], m[9], m[10]);
    if (!(std::abs(det) > 1e-12 * bound)) return "singular matrix (determinant " + std::to_string(det) + ")";
    return {};
}

}  // namespace kdrt::detail
