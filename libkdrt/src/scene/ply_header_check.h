// A check of a PLY file's header before Assimp reads it. Assimp 5.2's PLY
// reader loops forever on a header cut short (no end_header: a truncated
// download) and crashes on some malformed ones, and it trusts the element
// counts; so the header must be well formed (Turk 1994, "The PLY polygon file
// format") and its counts must fit in the bytes that follow.
#pragma once

#include <cstdint>
#include <string>

namespace kdrt::detail {

// Empty when the header is usable, else what is wrong with it. `head` is the
// start of the file (at least the header, when the file has one within the
// size read), `file_size` the whole file's size.
std::string ply_header_problem(const std::string& head, std::uintmax_t file_size);

// How many bytes of a PLY file to read for ply_header_problem.
inline constexpr std::size_t kPlyHeaderLimit = std::size_t{1} << 20;

}  // namespace kdrt::detail
