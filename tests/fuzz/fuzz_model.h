// The model importer's entry under libFuzzer: the bytes as a model file of a
// given extension, first through the format's bounds in this process (kdrt's
// own parsing, instrumented: it guides the fuzzer), then, when they pass,
// through kdrt::import_model as kdrt-render runs it: Assimp in the
// kdrt-import helper process. A crash, a sanitizer report, a hang or an
// allocation past the limits on kdrt's side is a finding; what Assimp does
// to its own process is an Error here (docs/IMPORT.md, "Isolation"), and any
// Error is fine. A model returned must be usable: indices in range, numbers
// finite. KDRT_FUZZ_IN_PROCESS=1 imports in this process instead, to hunt
// crashes inside Assimp that the bounds might yet foresee (its findings are
// mostly Assimp's own bugs).
#pragma once

#include "scene/assimp_import.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

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

inline void check_usable(const kdrt::ImportedModel& m) {
    for (const kdrt::MeshTriangle& t : m.mesh.triangles) {
        if (t.material >= m.materials.size()) __builtin_trap();
        for (int k = 0; k < 3; ++k)
            if (t.v[k] >= m.mesh.positions.size() || (t.n[k] != kdrt::kNoNormal && t.n[k] >= m.mesh.normals.size()))
                __builtin_trap();
    }
    for (const auto& p : m.mesh.positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
}

inline void import_as(const std::uint8_t* data, std::size_t size, const std::string& extension) {
    const std::filesystem::path file = scratch() / ("model." + extension);
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    static const bool in_process = std::getenv("KDRT_FUZZ_IN_PROCESS") != nullptr;
    if (!in_process && !kdrt::detail::model_bounds_problem(file, bytes).empty()) return;
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
    kdrt::ImportOptions options;
    options.isolation = in_process ? kdrt::ImportIsolation::InProcess : kdrt::ImportIsolation::ChildProcess;
    options.time_limit_s = 5;  // the product's own limit, below libFuzzer's -timeout
    try {
        check_usable(kdrt::import_model(file, kdrt::kIdentityTransform, options));
    } catch (const kdrt::Error&) {
    }
}

}  // namespace kdrt_fuzz
