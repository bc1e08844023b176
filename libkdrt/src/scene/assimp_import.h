// import_model's work in the process that runs Assimp: the kdrt-import
// helper (ImportIsolation::ChildProcess) or the caller (InProcess). The file
// is known to be a regular, non-empty file of a listed extension, and the
// transform to be affine (model_import.cpp checks both first).
#pragma once

#include <kdrt/model_import.h>

#include <array>
#include <filesystem>
#include <string>
#include <string_view>

namespace kdrt::detail {

// Whether kdrt checks the bounds of this format before Assimp reads it
// (docs/IMPORT.md, "Bounds"): PLY, OFF, glTF, GLB, FBX.
bool has_bounds(const std::filesystem::path& path);

// What in `file` (the whole model file at `path`) is beyond its format's
// bounds, or empty (model_header_check.h, gltf_bounds_check.h, fbx_bounds_check.h).
std::string model_bounds_problem(const std::filesystem::path& path, std::string_view file);

ImportedModel import_with_assimp(const std::filesystem::path& path, const std::array<double, 16>& transform,
                                 const ImportOptions& options);

}  // namespace kdrt::detail
