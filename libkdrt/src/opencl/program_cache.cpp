#include "opencl/program_cache.h"

#include "common/atomic_file.h"
#include "common/ms_since.h"
#include "opencl/cl_error.h"

#include <kdrt/version.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <functional>
#include <iterator>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

namespace kdrt::detail::ocl {

namespace fs = std::filesystem;

namespace {

constexpr std::array<char, 8> kMagic = {'K', 'D', 'R', 'T', 'C', 'L', 'B', 'N'};

// Writes the loading marker; no fsync: it has to outlive a crash of the
// process, not of the machine.
bool create_marker(const fs::path& marker) {
    // O_NONBLOCK: a FIFO put there fails the open instead of waiting for a reader.
    const int fd = ::open(marker.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0600);
    if (fd < 0) return false;
    const std::string pid = std::to_string(::getpid());
    const bool ok = ::write(fd, pid.data(), pid.size()) == static_cast<ssize_t>(pid.size());
    return ::close(fd) == 0 && ok;
}

// Creates missing directories with mode 0700 (compiled programs are loaded
// into the process: nobody else may write them). An existing directory must be
// a real directory owned by the user, writable by no one else. `problem`
// receives why the directory cannot be used.
std::optional<fs::path> usable_directory(const fs::path& dir, std::string* problem = nullptr) {
    if (dir.empty()) return std::nullopt;
    auto refuse = [&](const std::string& why) -> std::optional<fs::path> {
        if (problem) *problem = dir.string() + ": " + why;
        return std::nullopt;
    };
    fs::path partial;
    for (const fs::path& part : dir) {
        partial /= part;
        if (::mkdir(partial.c_str(), 0700) != 0 && errno != EEXIST)
            return refuse("cannot create " + partial.string() + ": " + std::strerror(errno));
    }
    struct stat st {};
    if (::lstat(dir.c_str(), &st) != 0) return refuse(std::strerror(errno));
    if (!S_ISDIR(st.st_mode)) return refuse("not a directory");
    if (st.st_uid != ::geteuid()) return refuse("owned by another user (uid " + std::to_string(st.st_uid) + ")");
    if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0) return refuse("writable by other users");
    if (::access(dir.c_str(), R_OK | W_OK | X_OK) != 0) return refuse(std::string("not usable: ") + std::strerror(errno));
    return dir;
}

// The entry is a regular file (not a link) owned by the user.
bool trusted_entry(const fs::path& file) {
    struct stat st {};
    return ::lstat(file.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == ::geteuid();
}

// Opens a cache file for reading, regular files only: O_NONBLOCK so that a
// FIFO put in the cache opens at once, then the type is checked on the
// descriptor. -1 with errno ENOENT when there is none, another errno when it
// is something else (ENODEV for a FIFO, device or socket).
int open_regular(const fs::path& file) {
    const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return -1;
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        errno = ENODEV;
        return -1;
    }
    return fd;
}

// The cache's secret: 32 random bytes in a 0600 file of the cache directory,
// made on first use. Entries carry an HMAC under it, not a plain checksum, so
// a binary altered by anyone who cannot read the secret (who recomputed a
// SHA-256, say) is refused before the driver sees it.
std::optional<Sha256Digest> cache_secret(const fs::path& dir) {
    const fs::path file = dir / kSecretFileName;
    for (int attempt = 0; attempt < 2; ++attempt) {
        const int fd = open_regular(file);
        if (fd >= 0) {
            struct stat st {};
            Sha256Digest secret{};
            const bool ok = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == ::geteuid() &&
                            (st.st_mode & 077) == 0 && st.st_size == static_cast<off_t>(secret.size()) &&
                            ::read(fd, secret.data(), secret.size()) == static_cast<ssize_t>(secret.size());
            ::close(fd);
            if (ok) return secret;
            return std::nullopt;  // not ours or damaged: work without the disk cache
        }
        if (errno != ENOENT) return std::nullopt;
        Sha256Digest secret{};
        std::random_device random;
        for (std::size_t i = 0; i < secret.size(); i += 4) {
            const unsigned r = random();
            for (std::size_t j = 0; j < 4; ++j) secret[i + j] = static_cast<std::uint8_t>(r >> (8 * j));
        }
        try {
            write_file_atomically(file, secret, 0600);  // a racing process may win: read back what is there
        } catch (const Error&) {
            return std::nullopt;
        }
    }
    return std::nullopt;
}

// A marker beside an entry while its binary is handed to the driver: a driver
// that crashes on a damaged binary cannot be caught in the process, but the
// marker outlives the crash, and the next run evicts the entry instead of
// crashing again. The marker holds the loading process's id.
fs::path loading_marker(const fs::path& file) { return fs::path(file.string() + ".loading"); }

enum class MarkerState { None, Live, Stale, Foreign };  // Foreign: not a regular file (a FIFO)

MarkerState marker_state(const fs::path& marker) {
    const int fd = open_regular(marker);
    if (fd < 0) return errno == ENOENT ? MarkerState::None : MarkerState::Foreign;
    char text[32] = {};
    const ssize_t n = ::read(fd, text, sizeof text - 1);
    ::close(fd);
    long pid = 0;
    if (n > 0) pid = std::strtol(text, nullptr, 10);
    if (pid <= 0 || pid == ::getpid()) return pid == ::getpid() ? MarkerState::Live : MarkerState::Stale;
    return (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM) ? MarkerState::Live : MarkerState::Stale;
}

std::optional<std::string> environment(const char* name) {
    const char* value = std::getenv(name);
    if (value == nullptr) return std::nullopt;
    return std::string(value);
}

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

void put_u64(std::vector<unsigned char>& out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

std::uint64_t get_le(const unsigned char* p, int bytes) {
    std::uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

// A length-prefixed field, so that no two field lists hash alike.
void hash_field(Sha256& hash, const std::string& field) {
    std::vector<unsigned char> length;
    put_u64(length, field.size());
    hash.update(length.data(), length.size());
    hash.update(field);
}

template <class F>
std::string query_or_empty(F&& f) {
    try {
        return f();
    } catch (const cl::Error&) {
        return {};
    }
}

std::string trim_log(std::string log) {
    while (!log.empty() && (log.back() == '\n' || log.back() == '\r' || log.back() == ' ' || log.back() == '\0')) {
        log.pop_back();
    }
    return log;
}

std::string build_log(const cl::Program& program, const cl::Device& device) {
    return trim_log(query_or_empty([&] { return program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device); }));
}

// The program's binary for `device`, or empty when the driver offers none.
std::vector<unsigned char> program_binary(const cl::Program& program, const cl::Device& device) {
    const std::vector<cl::Device> devices = program.getInfo<CL_PROGRAM_DEVICES>();
    std::vector<std::vector<unsigned char>> binaries = program.getInfo<CL_PROGRAM_BINARIES>();
    for (std::size_t i = 0; i < devices.size() && i < binaries.size(); ++i) {
        if (devices[i]() == device()) return std::move(binaries[i]);
    }
    return {};
}

std::optional<cl::Program> build_from_binary(const cl::Context& context, const ClDevice& device,
                                             const std::vector<unsigned char>& binary,
                                             const std::string& options, std::string& log) {
    try {
        const cl::Program::Binaries binaries{binary};
        std::vector<cl_int> status;
        cl::Program program(context, {device.device}, binaries, &status);
        program.build({device.device}, options.c_str());
        std::vector<cl::Kernel> kernels;
        program.createKernels(&kernels);  // a damaged binary may build but hold no usable kernel
        if (kernels.empty()) return std::nullopt;
        log = build_log(program, device.device);
        return program;
    } catch (const cl::Error&) {
        return std::nullopt;  // CL_INVALID_BINARY, or a driver that rejects its own old binary
    }
}

cl::Program build_from_source(const cl::Context& context, const ClDevice& device, const std::string& source,
                              const std::string& options, std::string& log) {
    cl::Program program(context, source);
    try {
        program.build({device.device}, options.c_str());
    } catch (const cl::Error& e) {
        const cl_int code = e.err();
        if (code != CL_BUILD_PROGRAM_FAILURE && code != CL_INVALID_BUILD_OPTIONS &&
            code != CL_COMPILER_NOT_AVAILABLE) {
            throw;
        }
        std::string failure_log = build_log(program, device.device);
        std::string message = "OpenCL program build failed on " + device.info.id + " (" + device.info.name + ", " +
                              device.info.platform + ", driver " + device.info.driver_version +
                              "): " + cl_error_name(code) + "\noptions: " + options + "\nbuild log:\n" +
                              (failure_log.empty() ? std::string("(empty)") : failure_log);
        throw ClBuildError(message, std::move(failure_log), options);
    }
    log = build_log(program, device.device);
    return program;
}

}  // namespace

ProgramCache::ProgramCache(std::optional<fs::path> dir)
    : dir_(dir ? usable_directory(*dir, &problem_) : default_directory()) {
    if (!problem_.empty()) problem_ = "kernel cache " + problem_ + "; compiling without it";
}

std::optional<fs::path> ProgramCache::default_directory() {
    if (auto kdrt = environment("KDRT_KERNEL_CACHE")) {
        if (kdrt->empty()) return std::nullopt;
        if (auto dir = usable_directory(*kdrt)) return dir;
    }
    if (auto xdg = environment("XDG_CACHE_HOME"); xdg && !xdg->empty()) {
        if (auto dir = usable_directory(fs::path(*xdg) / "kdrt" / "kernels")) return dir;
    }
    if (auto home = environment("HOME"); home && !home->empty()) {
        if (auto dir = usable_directory(fs::path(*home) / ".cache" / "kdrt" / "kernels")) return dir;
    }
    return std::nullopt;
}

std::string ProgramCache::full_options(const std::string& options) {
    return options.empty() ? std::string("-cl-std=CL1.2") : "-cl-std=CL1.2 " + options;
}

Sha256Digest ProgramCache::key(const ClDevice& device, const std::string& source, const std::string& full_options) {
    Sha256 hash;
    hash_field(hash, "kdrt program cache " + std::to_string(kCacheFormatVersion));
    hash_field(hash, KDRT_VERSION_STRING);
    hash_field(hash, device.info.platform);
    hash_field(hash, query_or_empty([&] { return device.platform.getInfo<CL_PLATFORM_VERSION>(); }));
    hash_field(hash, device.info.name);
    hash_field(hash, query_or_empty([&] { return device.device.getInfo<CL_DEVICE_VERSION>(); }));
    hash_field(hash, device.info.driver_version);
    hash_field(hash, full_options);
    hash_field(hash, source);
    return hash.finish();
}

BuiltProgram ProgramCache::build(const cl::Context& context, const ClDevice& device, const std::string& source,
                                 const std::string& options) const {
    const auto start = std::chrono::steady_clock::now();
    const std::string opts = full_options(options);
    BuiltProgram result;
    auto finish = [&] {
        result.compile_ms = ms_since(start);
        return result;
    };

    return guard_cl("building an OpenCL program for " + device.info.id + " (" + device.info.name + ")", [&] {
        std::optional<fs::path> file;
        Sha256Digest cache_key{};
        if (dir_) {
            cache_key = key(device, source, opts);
            file = *dir_ / (to_hex(cache_key) + ".clbin");
            result.cache_file = file->string();
            std::error_code ec;
            const fs::path marker = loading_marker(*file);
            const MarkerState state = marker_state(marker);
            if (state == MarkerState::Stale) {
                // A process died while loading this entry: never hand it to the driver again.
                fs::remove(*file, ec);
                fs::remove(marker, ec);
            }
            if (state == MarkerState::Foreign) {
                result.cache_warning = "kernel cache: " + marker.string() +
                                       " is not a regular file (a FIFO?); compiling without the cache";
                file.reset();
            } else if (state == MarkerState::Live) {
                file.reset();  // another build is loading it now: compile, leave the entry alone
            } else if (fs::exists(*file, ec)) {
                std::optional<std::vector<unsigned char>> binary;
                if (trusted_entry(*file)) binary = read_cache_file(*file, cache_key);
                if (binary && create_marker(marker)) {
                    auto program = build_from_binary(context, device, *binary, opts, result.build_log);
                    fs::remove(marker, ec);
                    if (program) {
                        result.program = std::move(*program);
                        result.cache_hit = true;
                        return finish();
                    }
                }
                fs::remove(*file, ec);  // bad, truncated, foreign or refused: never try it again
            }
        }

        result.program = build_from_source(context, device, source, opts, result.build_log);
        if (file) {
            const std::vector<unsigned char> binary = program_binary(result.program, device.device);
            std::string problem;
            if (!usable_directory(*dir_, &problem)) {  // in case it was removed since
                result.cache_warning = "kernel cache " + problem;
                result.cache_file.clear();
            } else if (binary.empty() || !write_cache_file(*file, cache_key, binary, &problem)) {
                if (!problem.empty()) result.cache_warning = "kernel cache: " + problem;
                result.cache_file.clear();
            }
        } else {
            result.cache_file.clear();
        }
        return finish();
    });
}

bool write_cache_file(const fs::path& path, const Sha256Digest& key, const std::vector<unsigned char>& binary,
                      std::string* problem) {
    std::vector<unsigned char> bytes;
    bytes.insert(bytes.end(), kMagic.begin(), kMagic.end());
    put_u32(bytes, kCacheFormatVersion);
    bytes.insert(bytes.end(), key.begin(), key.end());
    put_u64(bytes, binary.size());
    bytes.insert(bytes.end(), binary.begin(), binary.end());
    const std::optional<Sha256Digest> secret = cache_secret(path.parent_path());
    if (!secret) {
        if (problem) *problem = (path.parent_path() / kSecretFileName).string() + ": cannot be created or read";
        return false;
    }
    const Sha256Digest checksum = hmac_sha256(*secret, binary.data(), binary.size());
    bytes.insert(bytes.end(), checksum.begin(), checksum.end());
    try {
        write_file_atomically(path, bytes, 0600);
    } catch (const Error& e) {
        if (problem) *problem = e.what();
        return false;
    }
    return true;
}

std::optional<std::vector<unsigned char>> read_cache_file(const fs::path& path, const Sha256Digest& key) {
    const int fd = open_regular(path);
    if (fd < 0) return std::nullopt;
    struct stat st {};
    std::vector<unsigned char> bytes;
    if (::fstat(fd, &st) == 0 && st.st_size >= static_cast<off_t>(kCacheHeaderBytes + 32)) {
        bytes.resize(static_cast<std::size_t>(st.st_size));
        std::size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t n = ::pread(fd, bytes.data() + done, bytes.size() - done, static_cast<off_t>(done));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) break;
            done += static_cast<std::size_t>(n);
        }
        bytes.resize(done);
    }
    ::close(fd);
    if (bytes.size() < kCacheHeaderBytes + 32) return std::nullopt;
    const unsigned char* header = bytes.data();
    if (std::memcmp(header, kMagic.data(), kMagic.size()) != 0) return std::nullopt;
    if (get_le(header + 8, 4) != kCacheFormatVersion) return std::nullopt;
    if (std::memcmp(header + 12, key.data(), key.size()) != 0) return std::nullopt;
    const std::uint64_t length = get_le(header + 44, 8);
    if (length != bytes.size() - kCacheHeaderBytes - 32) return std::nullopt;
    std::vector<unsigned char> binary(bytes.begin() + kCacheHeaderBytes, bytes.end() - 32);
    Sha256Digest stored{};
    std::copy(bytes.end() - 32, bytes.end(), stored.begin());
    const std::optional<Sha256Digest> secret = cache_secret(path.parent_path());
    if (!secret || hmac_sha256(*secret, binary.data(), binary.size()) != stored) return std::nullopt;
    if (length == 0) return std::nullopt;  // no driver binary is empty
    return binary;
}

}  // namespace kdrt::detail::ocl
