#include "common/read_input_file.h"

#include "common/parallel_chunks.h"

#include <kdrt/error.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

namespace kdrt::detail {
namespace {

// Closes the descriptor on every path out of the readers below.
class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    ~FileDescriptor() {
        if (fd_ >= 0) ::close(fd_);
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    int get() const { return fd_; }
    void reset(int fd) {
        if (fd_ >= 0) ::close(fd_);
        fd_ = fd;
    }

private:
    int fd_;
};

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& problem) {
    throw Error(ErrorCode::Io, path.string() + ": " + problem);
}

// Opens `path` for reading and checks that it is a regular file of at most
// max_bytes; returns its size.
std::uint64_t open_input(const std::filesystem::path& path, const std::string& what, std::uint64_t max_bytes,
                         FileDescriptor& fd) {
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
    // The file type is then checked on the descriptor itself (no race with a
    // rename between a stat of the path and the open).
    fd.reset(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
    if (fd.get() < 0) fail(path, "cannot open: " + std::string(std::strerror(errno)));
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0) fail(path, "cannot stat: " + std::string(std::strerror(errno)));
    if (S_ISDIR(st.st_mode)) fail(path, "is a directory, not a " + what);
    if (!S_ISREG(st.st_mode)) fail(path, "is not a regular file (a pipe, socket or device), not a " + what);
    const auto size = static_cast<std::uint64_t>(st.st_size);
    if (size > max_bytes)
        fail(path, "is " + std::to_string(size) + " bytes, more than the " + std::to_string(max_bytes) +
                       "-byte limit for a " + what);
    return size;
}

// Reads up to `size` bytes at `offset` into `out`; returns how many (fewer at the end of the file).
std::size_t read_at(const std::filesystem::path& path, int fd, char* out, std::size_t size, std::uint64_t offset) {
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
        if (n < 0) {
            if (errno == EINTR) continue;
            fail(path, "read failed: " + std::string(std::strerror(errno)));
        }
        if (n == 0) break;
        done += static_cast<std::size_t>(n);
    }
    return done;
}

}  // namespace

std::string read_input_file(const std::filesystem::path& path, const std::string& what,
                            std::uint64_t max_bytes) {
    FileDescriptor fd(-1);
    const std::uint64_t size = open_input(path, what, max_bytes, fd);
    std::string bytes(static_cast<std::size_t>(size), '\0');
    // A file that shrank since fstat: keep what is there.
    bytes.resize(read_at(path, fd.get(), bytes.data(), bytes.size(), 0));
    return bytes;
}

InputBytes read_input_bytes(const std::filesystem::path& path, const std::string& what, std::uint64_t max_bytes) {
    FileDescriptor fd(-1);
    const auto size = static_cast<std::size_t>(open_input(path, what, max_bytes, fd));
    std::unique_ptr<char[]> data(new char[size == 0 ? 1 : size]);
    constexpr std::size_t kPiece = std::size_t{4} << 20;  // 4 MiB: a 73 MB mesh in 18 pieces
    std::vector<std::size_t> got(chunk_count(size, kPiece), 0);
    for_each_chunk(
        size,
        [&](std::size_t piece, std::size_t begin, std::size_t end) {
            got[piece] = read_at(path, fd.get(), data.get() + begin, end - begin, begin);
        },
        kPiece);
    for (std::size_t piece = 0; piece < got.size(); ++piece)
        if (got[piece] != std::min(kPiece, size - piece * kPiece))
            fail(path, "gave fewer bytes than the " + std::to_string(size) +
                           " its size said when it was opened (did it change while it was read?)");
    return InputBytes(std::move(data), size);
}

}  // namespace kdrt::detail
