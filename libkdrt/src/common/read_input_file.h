// Reading a whole input file (scene JSON, OBJ mesh) into memory, safely: only
// regular files are accepted, so a FIFO, a device such as /dev/zero or a
// directory is refused at once instead of blocking or growing memory without
// end, and the read is bounded by the size the file had when it was opened.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace kdrt::detail {

// Largest input file read_input_file accepts by default: far beyond any scene
// this project renders, small enough to fail clearly rather than with bad_alloc.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t{2} << 30;  // 2 GiB

// The file's bytes. `what` names the expected kind in messages ("scene file",
// "OBJ file"). Throws kdrt::Error(Io) naming the path: cannot open, not a
// regular file, larger than max_bytes, read failure.
std::string read_input_file(const std::filesystem::path& path, const std::string& what,
                            std::uint64_t max_bytes = kMaxInputFileBytes);

// A file's bytes in a buffer that is never zeroed first.
class InputBytes {
public:
    InputBytes(std::unique_ptr<char[]> data, std::size_t size) : data_(std::move(data)), size_(size) {}
    std::string_view view() const { return {data_.get(), size_}; }

private:
    std::unique_ptr<char[]> data_;
    std::size_t size_;
};

// read_input_file for big files (meshes): the same checks and errors, and a
// file of many megabytes is read in pieces by parallel tasks, so that copying
// it and faulting its pages in is not one thread's work. A file that shrinks
// while it is read is an error here (its pieces would no longer join up).
InputBytes read_input_bytes(const std::filesystem::path& path, const std::string& what,
                            std::uint64_t max_bytes = kMaxInputFileBytes);

}  // namespace kdrt::detail
