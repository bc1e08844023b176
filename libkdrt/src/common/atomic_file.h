// Writing a file so that it is either completely replaced or left as it was:
// the bytes go to a temporary file beside the target (same directory, so the
// rename cannot cross file systems), every write and the close are checked,
// the data is fsync'ed, and only then is the temporary renamed over the
// target. A full disk, a failing device or a kill -9 therefore never leaves a
// truncated or empty file where the previous one was; at worst a temporary
// ".NAME.tmp-XXXXXX" is left after a kill (temporary_file_pattern()).
//
// Targets that exist and are not regular files (device nodes such as
// /dev/full, FIFOs, directories, sockets) or are symbolic links are refused:
// replacing them would destroy what the link or node stands for.
#pragma once

#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <sys/types.h>

namespace kdrt::detail {

// Throws kdrt::Error(Io) naming `path` when it exists and is a symlink or not a
// regular file, or when its directory does not exist or cannot be written.
// Writes nothing.
void check_output_target(const std::filesystem::path& path);

// The file-name prefix and infix of temporaries for `target`:
// "." + filename + ".tmp-" (followed by 6 random characters and `suffix`).
std::string temporary_file_prefix(const std::filesystem::path& target);

class AtomicFile {
public:
    // Checks the target (check_output_target) and creates the temporary
    // (O_EXCL, `mode` filtered by the umask). `suffix` ends the temporary's
    // name, e.g. ".png" for writers that pick the format from the extension.
    explicit AtomicFile(std::filesystem::path target, std::string suffix = {}, mode_t mode = 0666);
    ~AtomicFile();  // removes the temporary unless commit() succeeded
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::filesystem::path& target() const { return target_; }
    // Where the data goes; another writer may open and fill this path
    // (commit() still flushes it to disk, through this object's descriptor).
    const std::filesystem::path& temporary() const { return temporary_; }

    // Appends; throws kdrt::Error(Io) naming the target and the OS error.
    void write(const void* data, std::size_t size);
    // fsync, close, rename over the target, fsync the directory. Throws
    // kdrt::Error(Io) (and removes the temporary) on any failure.
    void commit();

private:
    [[noreturn]] void fail(const std::string& what, int error);
    void discard() noexcept;

    std::filesystem::path target_, temporary_;
    int fd_ = -1;
    int live_slot_ = -1;  // its entry for remove_live_temporaries(), -1: none
    bool committed_ = false;
};

// Unlinks the temporary of every AtomicFile of this process that is neither
// committed nor discarded. Async-signal-safe (atomics and unlink only): for a
// handler of a signal that ends the process (SIGTERM from mpirun), which would
// otherwise leave those temporaries behind. Up to 64 live files are tracked.
void remove_live_temporaries() noexcept;

// The whole file in one call.
void write_file_atomically(const std::filesystem::path& target, std::span<const unsigned char> bytes,
                           mode_t mode = 0666);

}  // namespace kdrt::detail
