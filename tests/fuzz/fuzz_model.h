// The model importer's entry under libFuzzer: the bytes as a model file of a
// given extension, through kdrt::import_model in this process (the bounds of
// docs/IMPORT.md first, then Assimp), so that a crash, a sanitizer report, an
// allocation past -rss_limit_mb or a hang is a finding. Any Error is fine; a
// model returned must be usable: every index in range, every number finite.
#pragma once

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace kdrt_fuzz {

// A folder of this process's own for the file under test.
inline const std::filesystem::path& scratch() {
    static const std::filesystem::path dir = [] {
        std::filesystem::path d = std::filesystem::temp_directory_path() / ("kdrt-fuzz-model-" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

inline void import_as(const std::uint8_t* data, std::size_t size, const std::string& extension) {
    const std::filesystem::path file = scratch() / ("model." + extension);
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    kdrt::ImportOptions options;
    options.isolation = kdrt::ImportIsolation::InProcess;
    try {
        const kdrt::ImportedModel m = kdrt::import_model(file, kdrt::kIdentityTransform, options);
        for (const kdrt::MeshTriangle& t : m.mesh.triangles) {
            if (t.material >= m.materials.size()) __builtin_trap();
            for (int k = 0; k < 3; ++k)
                if (t.v[k] >= m.mesh.positions.size() || (t.n[k] != kdrt::kNoNormal && t.n[k] >= m.mesh.normals.size()))
                    __builtin_trap();
        }
        for (const auto& p : m.mesh.positions)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
    } catch (const kdrt::Error&) {
    }
}

}  // namespace kdrt_fuzz
