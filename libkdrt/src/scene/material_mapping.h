// The rule of docs/IMPORT.md that turns a material read by Assimp (MTL's
// Phong-style keys, glTF's metallic-roughness keys, or the generic colour
// keys of other formats) into one of FORMAT.md's Whitted materials.
#pragma once

#include <kdrt/scene.h>

struct aiMaterial;

namespace kdrt::detail {

// The Whitted material for `source`; its name is left empty for the caller.
// Always satisfies validate()'s ranges, whatever numbers the file holds.
Material whitted_material(const aiMaterial& source);

}  // namespace kdrt::detail
