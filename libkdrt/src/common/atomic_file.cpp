#include "common/atomic_file.h"

#include <kdrt/error.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

namespace kdrt::detail {

namespace fs = std::filesystem;

namespace {

fs::path directory_of(const fs::path& path) {
    return path.has_parent_path() ? path.parent_path() : fs::path(".");
}

std::string os_error(int error) { return std::strerror(error); }

std::string random_suffix() {
    static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    thread_local std::mt19937_64 random{std::random_device{}()};
    std::string s(6, '0');
    for (char& c : s) c = kAlphabet[random() % (sizeof kAlphabet - 1)];
    return s;
}

// The live temporaries, for remove_live_temporaries() in a signal handler: a
// slot is taken (free -> filling -> live) by a new AtomicFile and freed when
// it commits or discards; the handler claims a live slot (live -> claimed)
// before it reads the path, so the slot cannot be refilled under it.
enum : int { kFree, kFilling, kLive, kClaimed };
struct LiveTemporary {
    std::atomic<int> state{kFree};
    char path[4096];
};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch a lock-free atomic");
LiveTemporary live_temporaries[64];

int register_live(const fs::path& temporary) noexcept {
    const std::string& path = temporary.native();
    if (path.size() >= sizeof live_temporaries[0].path) return -1;
    for (int i = 0; i < static_cast<int>(std::size(live_temporaries)); ++i) {
        LiveTemporary& slot = live_temporaries[i];
        int expected = kFree;
        if (!slot.state.compare_exchange_strong(expected, kFilling)) continue;
        std::memcpy(slot.path, path.c_str(), path.size() + 1);
        slot.state.store(kLive);
        return i;
    }
    return -1;
}

void unregister_live(int& slot) noexcept {
    if (slot < 0) return;
    int expected = kLive;
    // Claimed: the process is ending in a signal handler; the slot stays taken.
    live_temporaries[slot].state.compare_exchange_strong(expected, kFree);
    slot = -1;
}

}  // namespace

void remove_live_temporaries() noexcept {
    for (LiveTemporary& slot : live_temporaries) {
        int expected = kLive;
        if (slot.state.compare_exchange_strong(expected, kClaimed)) ::unlink(slot.path);
    }
}

void check_output_target(const fs::path& path) {
    if (path.empty()) throw Error(ErrorCode::Io, "empty output file name");
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0) {
        if (S_ISLNK(st.st_mode))
            throw Error(ErrorCode::Io, path.string() + ": is a symbolic link; refusing to replace it");
        if (S_ISDIR(st.st_mode)) throw Error(ErrorCode::Io, path.string() + ": is a directory");
        if (!S_ISREG(st.st_mode))
            throw Error(ErrorCode::Io, path.string() + ": is not a regular file (a device, FIFO or socket); "
                                                       "refusing to replace it");
    } else if (errno != ENOENT) {
        throw Error(ErrorCode::Io, path.string() + ": " + os_error(errno));
    }
    const fs::path dir = directory_of(path);
    struct stat ds {};
    if (::stat(dir.c_str(), &ds) != 0)
        throw Error(ErrorCode::Io, path.string() + ": directory " + dir.string() + ": " + os_error(errno));
    if (!S_ISDIR(ds.st_mode))
        throw Error(ErrorCode::Io, path.string() + ": " + dir.string() + " is not a directory");
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
        throw Error(ErrorCode::Io, path.string() + ": directory " + dir.string() + " is not writable: " +
                                       os_error(errno));
}

std::string temporary_file_prefix(const fs::path& target) {
    // Built by appending: GCC 12 warns falsely (-Wrestrict) on "." + string + ".tmp-".
    std::string prefix(1, '.');
    prefix.append(target.filename().string());
    prefix.append(".tmp-");
    return prefix;
}

AtomicFile::AtomicFile(fs::path target, std::string suffix, mode_t mode) : target_(std::move(target)) {
    check_output_target(target_);
    const fs::path dir = directory_of(target_);
    for (int attempt = 0; attempt < 100; ++attempt) {
        temporary_ = dir / (temporary_file_prefix(target_) + random_suffix() + suffix);
        fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        if (fd_ >= 0) {
            live_slot_ = register_live(temporary_);
            return;
        }
        if (errno != EEXIST) break;
    }
    const int error = errno;
    throw Error(ErrorCode::Io, target_.string() + ": cannot create a temporary file in " + dir.string() + ": " +
                                   os_error(error));
}

AtomicFile::~AtomicFile() {
    if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (!temporary_.empty()) ::unlink(temporary_.c_str());
    unregister_live(live_slot_);
}

void AtomicFile::fail(const std::string& what, int error) {
    discard();
    throw Error(ErrorCode::Io, target_.string() + ": " + what + ": " + os_error(error) +
                                   " (the previous file, if any, is unchanged)");
}

void AtomicFile::write(const void* data, std::size_t size) {
    if (fd_ < 0) throw Error(ErrorCode::Io, target_.string() + ": write after commit or failure");
    const auto* p = static_cast<const unsigned char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd_, p, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            fail("cannot write", errno);
        }
        if (n == 0) fail("cannot write", EIO);
        p += n;
        size -= static_cast<std::size_t>(n);
    }
}

void AtomicFile::commit() {
    if (fd_ < 0) throw Error(ErrorCode::Io, target_.string() + ": commit after commit or failure");
    if (::fsync(fd_) != 0) fail("cannot write", errno);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("cannot write", errno);
    // A symlink or device put at the target while we wrote is not replaced either.
    try {
        check_output_target(target_);
    } catch (const Error&) {
        discard();
        throw;
    }
    if (::rename(temporary_.c_str(), target_.c_str()) != 0) fail("cannot replace the file", errno);
    committed_ = true;
    unregister_live(live_slot_);
    // Make the rename itself durable; a failure here loses nothing already written.
    const int dir = ::open(directory_of(target_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
        ::fsync(dir);
        ::close(dir);
    }
}

void write_file_atomically(const fs::path& target, std::span<const unsigned char> bytes, mode_t mode) {
    AtomicFile file(target, {}, mode);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

}  // namespace kdrt::detail
