// Building OpenCL programs, with a disk cache of device binaries.
//
// The cache key is a SHA-256 of everything that can change the binary: the
// platform (name, version), the device (name, version), the driver version,
// the complete build options, the source and the kdrt version. Entries are
// written atomically (temporary file + rename) and verified in full before
// use; a bad entry is deleted and the program rebuilt from source, and a
// binary the driver refuses also falls back to the source.
//
// Trust: directories are created 0700 and used only when owned by the user
// and not writable by others; entries that are not regular files owned by the
// user are evicted. Entries carry an HMAC under a secret kept in the
// directory (mode 0600), so an altered binary with a recomputed plain
// checksum is refused; someone who can read the secret (the user, root) can
// still forge an entry, and a binary that crashes the driver while loading
// cannot be caught in the process, so a marker file
// (ENTRY.loading, the loader's pid) brackets each load and the next run
// evicts an entry whose loader died: such an entry costs one crash, not all. Kernels are
// specialised with -D options, which are part of the key (as in LuxCoreRender).
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_devices.h"
#include "opencl/sha256.h"

#include <kdrt/error.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace kdrt::detail::ocl {

// A program that failed to compile from source: ErrorCode::Device, with a
// message holding the device, the options and the complete build log.
class ClBuildError : public Error {
public:
    ClBuildError(const std::string& message, std::string log, std::string options)
        : Error(ErrorCode::Device, message), log_(std::move(log)), options_(std::move(options)) {}
    const std::string& log() const noexcept { return log_; }
    const std::string& options() const noexcept { return options_; }  // as passed to clBuildProgram

private:
    std::string log_;
    std::string options_;
};

struct BuiltProgram {
    cl::Program program;      // built for the requested device
    double compile_ms = 0.0;  // wall time of build(): lookup, load or compile, store
    bool cache_hit = false;   // built from a cached binary
    std::string cache_file;   // the entry read or written; empty without a disk cache
    std::string build_log;    // the driver's log of the successful build (warnings), may be empty
    std::string cache_warning;  // why the disk cache could not store the program (directory, OS error), or empty
};

class ProgramCache {
public:
    // dir: the cache directory, created if missing; std::nullopt means
    // default_directory(), an empty path means no disk cache. When the
    // directory cannot be created the cache works without a disk cache.
    explicit ProgramCache(std::optional<std::filesystem::path> dir = std::nullopt);

    // $KDRT_KERNEL_CACHE if set (set but empty: no disk cache), else
    // $XDG_CACHE_HOME/kdrt/kernels, else $HOME/.cache/kdrt/kernels; the first
    // that can be created. std::nullopt when none can.
    static std::optional<std::filesystem::path> default_directory();

    // The directory in use, or std::nullopt when working without one.
    const std::optional<std::filesystem::path>& directory() const { return dir_; }
    // Why an explicitly given directory cannot be used (OS error, owner,
    // permissions), or empty.
    const std::string& problem() const { return problem_; }

    // Builds `source` for `device` (which must be in `context`) with
    // "-cl-std=CL1.2 " + options. Throws ClBuildError when the source does not
    // compile, kdrt::Error(ErrorCode::Device) for any other OpenCL failure.
    // Disk cache failures are not errors: the program is then just compiled.
    BuiltProgram build(const cl::Context& context, const ClDevice& device, const std::string& source,
                       const std::string& options) const;

    // The options passed to clBuildProgram for caller options `options`.
    static std::string full_options(const std::string& options);
    // The cache key for a build with the given full options.
    static Sha256Digest key(const ClDevice& device, const std::string& source, const std::string& full_options);

private:
    std::string problem_;
    std::optional<std::filesystem::path> dir_;
};

// ---- the cache file, exposed for tests --------------------------------------
// Layout, integers little-endian:
//   "KDRTCLBN" (8 bytes) | format version u32 | key (32 bytes) |
//   binary length u64 | binary | HMAC-SHA-256 of the binary (32 bytes) under
//   the directory's secret (kSecretFileName, 32 random bytes, mode 0600)
inline constexpr std::uint32_t kCacheFormatVersion = 2;
inline constexpr const char* kSecretFileName = "cache-secret";
inline constexpr std::size_t kCacheHeaderBytes = 8 + 4 + 32 + 8;

// Writes the entry (mode 0600) through a temporary file in the same directory
// and a rename; false (nothing left behind, `problem` says why) on any failure.
bool write_cache_file(const std::filesystem::path& path, const Sha256Digest& key,
                      const std::vector<unsigned char>& binary, std::string* problem = nullptr);
// The binary, if `path` exists and every field checks out for `key`.
std::optional<std::vector<unsigned char>> read_cache_file(const std::filesystem::path& path,
                                                          const Sha256Digest& key);

}  // namespace kdrt::detail::ocl
