// The OBJ parser behind load_obj_mesh, on text already in memory (the OBJ
// fuzzer calls it directly; load_obj_mesh adds the safe file read).
#pragma once

#include <kdrt/scene.h>

#include <array>
#include <filesystem>
#include <string>
#include <string_view>

namespace kdrt::detail {

// `origin` names the text in messages ("<origin>:<line>: <problem>").
Mesh parse_obj_mesh(std::string_view text, const std::filesystem::path& origin,
                    const std::array<double, 16>& transform, MaterialId material);

}  // namespace kdrt::detail
