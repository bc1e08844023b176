// Importing models made elsewhere (OBJ+MTL, glTF 2.0, PLY, STL, ...) through
// Assimp: their triangles, their materials mapped onto FORMAT.md's Whitted
// materials, their cameras and point lights. docs/IMPORT.md is the contract:
// which formats, the material rule, the default camera and light, what is
// skipped and what is an error.
#pragma once

#include <kdrt/export.h>
#include <kdrt/aabb.h>
#include <kdrt/scene.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace kdrt {

// The row-major identity, the default transform.
inline constexpr std::array<double, 16> kIdentityTransform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// A camera found in a model file, already in the model's (transformed) space.
struct ModelCamera {
    std::string name;
    Camera camera;
    double aspect = 0.0;        // width / height the file asks for, 0 = not given
    bool orthographic = false;  // kdrt has pinhole cameras only: such a camera cannot be used
};

// What an import did, for messages and reports.
struct ImportStats {
    std::size_t triangles = 0;
    std::size_t meshes = 0;            // mesh instances placed by the node tree
    std::size_t materials = 0;         // materials used by the triangles
    std::size_t cameras = 0;
    std::size_t lights = 0;            // point lights made (directional and spot lights included)
    std::size_t skipped_points = 0;    // point primitives: kdrt renders triangles only
    std::size_t skipped_lines = 0;     // line primitives
    std::size_t skipped_lights = 0;    // ambient and area lights
    std::size_t flat_triangles = 0;    // triangles whose vertex normals had zero length: geometric normal used
    std::vector<std::string> warnings; // e.g. a material library that was not found
};

struct ImportedModel {
    // All triangles in one mesh, in node-tree order (docs/IMPORT.md); each
    // triangle's material indexes `materials` below, not a scene's list.
    Mesh mesh;
    std::vector<Material> materials;  // named "<file name>:<material name>", unique within the model
    std::vector<ModelCamera> cameras; // in the file's order (the numbers of --camera)
    std::vector<PointLight> lights;
    Aabb bounds;                      // of the transformed positions
    ImportStats stats;
};

// The file extensions import_model accepts (lower case, without the dot).
KDRT_API const std::vector<std::string>& model_file_extensions();

// True when the path's extension (any case) is one of model_file_extensions():
// where kdrt-render and scene files route a path to import_model.
KDRT_API bool is_model_file(const std::filesystem::path& path);

// Where Assimp parses the file (docs/IMPORT.md, "Isolation").
enum class ImportIsolation {
    // In a child process, the kdrt-import helper installed with libkdrt: a
    // crash, an abort or an exhausted limit of the parser is an Error naming
    // the file, never the end of the calling process.
    ChildProcess,
    // In the calling process, on its stack: the same bounds are checked
    // first, but a parser crash they do not foresee ends the process.
    InProcess,
};

struct ImportOptions {
    // Files a model names (an OBJ's material library, a glTF's buffers and
    // images) are read only from the model's folder and its subfolders,
    // symbolic links resolved; true allows any file.
    bool allow_outside_files = false;
    ImportIsolation isolation = ImportIsolation::ChildProcess;
    // ChildProcess: the helper's address space (RLIMIT_AS) in bytes; 0: half
    // the physical memory, at most 16 GiB. Beyond it: Error(ResourceLimit).
    std::uint64_t memory_limit = 0;
    // ChildProcess: wall-clock seconds the import may take, then it is
    // stopped with Error(ResourceLimit); 0: no limit.
    double time_limit_s = 600.0;
    // Polled about ten times a second while the helper runs (InProcess:
    // between the nodes of the model's tree, not inside Assimp's parser);
    // returning false stops the import with Error(Cancelled).
    std::function<bool()> keep_going;
};

// Imports a model file. Positions are transformed by the node tree and then by
// `transform` (row-major affine, as FORMAT.md's mesh transform; normals by
// the inverse transpose). Throws kdrt::Error(Io) when the file cannot be read
// and kdrt::Error(InvalidScene) when it is malformed or has no triangles or
// the parser crashed on it, Error(ResourceLimit) past a limit of `options`,
// Error(Unsupported) when the helper of ImportIsolation::ChildProcess is not
// installed; every message starts with the file's path.
KDRT_API ImportedModel import_model(const std::filesystem::path& path,
                                    const std::array<double, 16>& transform = kIdentityTransform,
                                    const ImportOptions& options = {});

// Adds an imported model to a scene as one mesh: its materials are appended
// (renamed with a suffix where a name is taken) unless `override_material`
// gives every triangle that one. Returns the object id of the first triangle.
KDRT_API std::uint32_t add_model(Scene& scene, ImportedModel model,
                                 std::optional<MaterialId> override_material = std::nullopt);

struct ModelSceneOptions {
    // Which of the file's cameras (ImportedModel::cameras index); none: the
    // first perspective camera, else a default camera framing the bounds.
    std::optional<int> camera;
    ImportOptions import{};
};

// A whole scene from a model file, for rendering it without a scene file:
// its materials, triangles, camera and point lights, with the defaults of
// docs/IMPORT.md where the file has none. `stats`, when given, receives the
// import's counts and warnings.
KDRT_API Scene scene_from_model(const std::filesystem::path& path, const ModelSceneOptions& options = {},
                                ImportStats* stats = nullptr);

// The default camera of docs/IMPORT.md: looks at the centre of `bounds` from
// the +z side, up +y, far enough that the bounding sphere fits the field of
// view with a margin.
KDRT_API Camera default_model_camera(const Aabb& bounds, double aspect);

// The default light of docs/IMPORT.md: white, at the camera raised by the
// bounding radius along the camera's up direction.
KDRT_API PointLight default_model_light(const Camera& camera, const Aabb& bounds);

}  // namespace kdrt
