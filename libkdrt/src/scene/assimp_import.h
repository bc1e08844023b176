// import_model's work in the process that runs Assimp: the kdrt-import
// helper (ImportIsolation::ChildProcess) or the caller (InProcess). The file
// is known to be a regular, non-empty file of a listed extension, and the
// transform to be affine (model_import.cpp checks both first).
#pragma once

#include <kdrt/model_import.h>

#include <array>
#include <filesystem>

namespace kdrt::detail {

ImportedModel import_with_assimp(const std::filesystem::path& path, const std::array<double, 16>& transform,
                                 const ImportOptions& options);

}  // namespace kdrt::detail
