#include "opencl/program_cache.h"

#include "opencl/cl_error.h"

#include <kdrt/version.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <thread>

namespace kdrt::detail::ocl {

namespace fs = std::filesystem;

namespace {

constexpr std::array<char, 8> kMagic = {'K', 'D', 'R', 'T', 'C', 'L', 'B', 'N'};

std::optional<fs::path> usable_directory(const fs::path& dir) {
    if (dir.empty()) return std::nullopt;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir, ec)) return std::nullopt;
    return dir;
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

std::string temporary_name(const fs::path& path) {
    static std::atomic<unsigned> counter{0};
    thread_local std::mt19937_64 random{std::random_device{}() ^
                                        std::hash<std::thread::id>{}(std::this_thread::get_id())};
    return path.filename().string() + ".tmp-" + std::to_string(random()) + "-" + std::to_string(++counter);
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
    : dir_(dir ? usable_directory(*dir) : default_directory()) {}

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
        result.compile_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
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
            if (fs::exists(*file, ec)) {
                if (auto binary = read_cache_file(*file, cache_key)) {
                    if (auto program = build_from_binary(context, device, *binary, opts, result.build_log)) {
                        result.program = std::move(*program);
                        result.cache_hit = true;
                        return finish();
                    }
                }
                fs::remove(*file, ec);  // bad, truncated or refused: never try it again
            }
        }

        result.program = build_from_source(context, device, source, opts, result.build_log);
        if (file) {
            const std::vector<unsigned char> binary = program_binary(result.program, device.device);
            std::error_code ec;
            fs::create_directories(*dir_, ec);  // in case it was removed since
            if (binary.empty() || !write_cache_file(*file, cache_key, binary)) result.cache_file.clear();
        }
        return finish();
    });
}

bool write_cache_file(const fs::path& path, const Sha256Digest& key, const std::vector<unsigned char>& binary) {
    std::vector<unsigned char> header;
    header.insert(header.end(), kMagic.begin(), kMagic.end());
    put_u32(header, kCacheFormatVersion);
    header.insert(header.end(), key.begin(), key.end());
    put_u64(header, binary.size());
    const Sha256Digest checksum = sha256(binary.data(), binary.size());

    const fs::path temporary = path.parent_path() / temporary_name(path);
    std::error_code ec;
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) return false;
        out.write(reinterpret_cast<const char*>(header.data()), static_cast<std::streamsize>(header.size()));
        out.write(reinterpret_cast<const char*>(binary.data()), static_cast<std::streamsize>(binary.size()));
        out.write(reinterpret_cast<const char*>(checksum.data()), static_cast<std::streamsize>(checksum.size()));
        out.close();
        if (!out) {
            fs::remove(temporary, ec);
            return false;
        }
    }
    fs::rename(temporary, path, ec);
    if (ec) {
        fs::remove(temporary, ec);
        return false;
    }
    return true;
}

std::optional<std::vector<unsigned char>> read_cache_file(const fs::path& path, const Sha256Digest& key) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec || size < kCacheHeaderBytes + 32) return std::nullopt;

    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    std::array<unsigned char, kCacheHeaderBytes> header{};
    if (!in.read(reinterpret_cast<char*>(header.data()), static_cast<std::streamsize>(header.size()))) {
        return std::nullopt;
    }
    if (std::memcmp(header.data(), kMagic.data(), kMagic.size()) != 0) return std::nullopt;
    if (get_le(header.data() + 8, 4) != kCacheFormatVersion) return std::nullopt;
    if (std::memcmp(header.data() + 12, key.data(), key.size()) != 0) return std::nullopt;
    const std::uint64_t length = get_le(header.data() + 44, 8);
    if (length != size - kCacheHeaderBytes - 32) return std::nullopt;

    std::vector<unsigned char> binary(static_cast<std::size_t>(length));
    Sha256Digest stored{};
    if (!in.read(reinterpret_cast<char*>(binary.data()), static_cast<std::streamsize>(binary.size())) ||
        !in.read(reinterpret_cast<char*>(stored.data()), static_cast<std::streamsize>(stored.size()))) {
        return std::nullopt;
    }
    if (sha256(binary.data(), binary.size()) != stored) return std::nullopt;
    if (length == 0) return std::nullopt;  // no driver binary is empty
    return binary;
}

}  // namespace kdrt::detail::ocl
