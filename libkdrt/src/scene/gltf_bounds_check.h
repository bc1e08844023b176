// Bounds on a glTF file before Assimp reads it (docs/IMPORT.md, "Bounds").
// Assimp 5.2 parses glTF JSON and converts the node tree recursively (deep
// nesting overflows its stack), copies a node once per path that reaches it
// (children shared level after level make exponentially many copies of a
// small file), allocates a GLB chunk or a buffer from its declared length
// before comparing it with the file, and indexes KHR_texture_transform's
// arrays without checking their length (an assertion of its JSON library
// aborts). These checks refuse such files with a message; what they do not
// foresee is left to the import's process isolation (import_process.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace kdrt::detail {

inline constexpr std::size_t kMaxGltfJsonDepth = 128;           // nesting of arrays and objects
inline constexpr std::size_t kMaxGltfNodeDepth = 512;           // levels of the node hierarchy
inline constexpr std::uint64_t kMaxGltfNodeInstances = 1000000;  // nodes once every shared child is copied
inline constexpr std::uint64_t kMaxGltfUnbackedBytes = std::uint64_t{1} << 28;  // accessors without a bufferView

// Empty when the file is within the bounds, else what is not. `file` is the
// whole .gltf (JSON text) or .glb (binary) file; `folder` is where its
// relative buffer URIs point, for their sizes.
std::string gltf_bounds_problem(std::string_view file, bool binary, const std::filesystem::path& folder);

}  // namespace kdrt::detail
