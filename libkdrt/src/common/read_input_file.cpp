#include "common/read_input_file.h"

#include <kdrt/error.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace kdrt::detail {
namespace {

// Closes the descriptor on every path out of read_input_file.
class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    ~FileDescriptor() {
        if (fd_ >= 0) ::close(fd_);
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    int get() const { return fd_; }

private:
    int fd_;
};

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& problem) {
    throw Error(ErrorCode::Io, path.string() + ": " + problem);
}

}  // namespace

std::string read_input_file(const std::filesystem::path& path, const std::string& what,
                            std::uint64_t max_bytes) {
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
    // The file type is then checked on the descriptor itself (no race with a
    // rename between a stat of the path and the open).
    FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
    if (fd.get() < 0) fail(path, "cannot open: " + std::string(std::strerror(errno)));
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0) fail(path, "cannot stat: " + std::string(std::strerror(errno)));
    if (S_ISDIR(st.st_mode)) fail(path, "is a directory, not a " + what);
    if (!S_ISREG(st.st_mode)) fail(path, "is not a regular file (a pipe, socket or device), not a " + what);
    const auto size = static_cast<std::uint64_t>(st.st_size);
    if (size > max_bytes)
        fail(path, "is " + std::to_string(size) + " bytes, more than the " + std::to_string(max_bytes) +
                       "-byte limit for a " + what);

    std::string bytes(static_cast<std::size_t>(size), '\0');
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::read(fd.get(), bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            fail(path, "read failed: " + std::string(std::strerror(errno)));
        }
        if (n == 0) break;  // the file shrank since fstat: keep what is there
        done += static_cast<std::size_t>(n);
    }
    bytes.resize(done);
    return bytes;
}

}  // namespace kdrt::detail
