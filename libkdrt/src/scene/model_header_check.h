// Checks of PLY and OFF headers before Assimp reads the file. Assimp 5.2's
// PLY reader loops forever on a header cut short (no end_header: a truncated
// download) and crashes on some malformed ones; its PLY and OFF readers trust
// the element counts, and an OFF file claiming 10^11 vertices makes it
// allocate and loop for minutes. So a header must be well formed (Turk 1994,
// "The PLY polygon file format"; the Geomview OFF format) and its counts must
// fit in the bytes that follow.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace kdrt::detail {

// Empty when the header is usable, else what is wrong with it. `head` is the
// start of the file (at least the header, when the file has one within the
// size read), `file_size` the whole file's size.
std::string ply_header_problem(const std::string& head, std::uintmax_t file_size);

// Empty when every list of a PLY file's body fits in the bytes that follow
// its length (Assimp reserves a list's items from the length alone), else
// where the first one does not. `file` is the whole file.
std::string ply_body_problem(std::string_view file);

// Empty when an OFF file's header is usable, else what is wrong with it.
std::string off_header_problem(const std::string& head, std::uintmax_t file_size);

// How many bytes of a file to read for these checks.
inline constexpr std::size_t kHeaderLimit = std::size_t{1} << 20;

}  // namespace kdrt::detail
