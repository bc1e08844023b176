// libFuzzer target: OBJ text through the parser behind kdrt::load_obj_mesh.
// The first byte picks the transform (identity, or a scale and shear that
// sends large coordinates to infinity) so that both paths are covered.
#include "scene/parse_obj_mesh.h"

#include <kdrt/error.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    static const std::array<double, 16> sheared{1e300, 2, 0, 1, 0, 1, 0, -2, 0, 0.5, 3, 0, 0, 0, 0, 1};
    const std::string text(reinterpret_cast<const char*>(data), size);
    const bool shear = size > 0 && (data[0] & 1);
    try {
        const kdrt::Mesh m = kdrt::detail::parse_obj_mesh(text, "fuzz.obj", shear ? sheared : identity, 0);
        // What the loader returns must be usable: indices in range.
        for (const kdrt::MeshTriangle& t : m.triangles)
            for (int k = 0; k < 3; ++k)
                if (t.v[k] >= m.positions.size() || (t.n[k] != kdrt::kNoNormal && t.n[k] >= m.normals.size()))
                    __builtin_trap();
    } catch (const kdrt::Error&) {
    }
    return 0;
}
