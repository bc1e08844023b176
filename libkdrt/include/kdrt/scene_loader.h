// Reading scene files (FORMAT.md, "kdrt-scene/1") and their OBJ meshes.
#pragma once

#include <kdrt/export.h>
#include <kdrt/model_import.h>
#include <kdrt/scene.h>

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt {

struct SceneLoadOptions {
    ImportOptions import{};  // how the scene's "model" meshes are imported (kdrt/model_import.h)
    // When given, receives the warnings of the models the scene places (a
    // material library not found), each naming the scene, the place and the model.
    std::vector<std::string>* warnings = nullptr;
};

// Loads and validates a scene file. Strict: unknown keys, wrong types, wrong
// vector lengths, out-of-range values, undefined materials and missing or
// malformed OBJ files are rejected with kdrt::Error(InvalidScene or Io) whose
// message names the file, the place ("spheres[3].radius") and the problem.
KDRT_API Scene load_scene(const std::filesystem::path& path, const SceneLoadOptions& options = {});

// Parses scene JSON text; OBJ paths are resolved against base_dir.
// `origin` names the source in messages.
KDRT_API Scene parse_scene(const std::string& json_text, const std::filesystem::path& base_dir,
                           const std::string& origin = "<memory>", const SceneLoadOptions& options = {});

// Loads an OBJ file as a mesh: positions transformed by the row-major affine
// `transform` (normals by its inverse transpose), polygons fanned into triangles,
// every triangle given `material`.
KDRT_API Mesh load_obj_mesh(const std::filesystem::path& path, const std::array<double, 16>& transform,
                            MaterialId material);

}  // namespace kdrt
