// Bounds on an FBX file before Assimp reads it (docs/IMPORT.md, "Bounds").
// Assimp 5.2 sizes an array from its declared element count before it
// inflates or copies it (a small file can ask for gigabytes), asserts that a
// raw array's bytes match its count (a changed count aborts the process), and
// parses nested records recursively. Binary files: every record lies inside
// its parent, every property inside its record's property list, a raw array
// holds exactly count x element bytes and a deflated one at most 1032 times
// its compressed size (deflate's largest ratio). Text files: braces nest at
// most kMaxFbxDepth deep and an array's "*N" count fits in the bytes left.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace kdrt::detail {

inline constexpr std::size_t kMaxFbxDepth = 128;

// Empty when the file is within the bounds, else what is not. `file` is the whole file.
std::string fbx_bounds_problem(std::string_view file);

}  // namespace kdrt::detail
