// The OpenCL host infrastructure (libkdrt/src/opencl): error names, device
// enumeration and selection, kernel embedding, the program cache and the
// buffer guard. Device tests skip with a warning when no OpenCL platform is
// installed.
#include "opencl/cl_devices.h"
#include "opencl/cl_error.h"
#include "opencl/embedded_cl.h"
#include "opencl/kernel_variant.h"
#include "opencl/program_cache.h"
#include "opencl/sha256.h"

#include <kdrt/device.h>
#include <kdrt/error.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace kdrt;
using namespace kdrt::detail::ocl;

namespace {

// The OpenCL devices, or empty after a WARN that the calling test skips.
std::vector<ClDevice> devices_or_warn() {
    std::vector<ClDevice> devices = enumerate_devices();
    if (devices.empty()) WARN("no OpenCL platform/device found: skipping this OpenCL device test");
    return devices;
}

struct TempDir {
    fs::path path;
    TempDir() {
        std::random_device random;
        path = fs::temp_directory_path() / ("kdrt-test-opencl-" + std::to_string(random()) + "-" +
                                            std::to_string(random()));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
};

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<unsigned char> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

const char* const kTinyKernel =
    "__kernel void add_one(__global int* x) {\n"
    "    x[get_global_id(0)] += 1;\n"
    "}\n";

// Runs add_one over {1, 2, 3, 4}: the program is not only built but usable.
std::vector<int> run_add_one(const cl::Context& context, const ClDevice& device, const cl::Program& program) {
    std::vector<int> data = {1, 2, 3, 4};
    cl::CommandQueue queue(context, device.device);
    cl::Buffer buffer(context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, data.size() * sizeof(int), data.data());
    cl::Kernel kernel(program, "add_one");
    kernel.setArg(0, buffer);
    queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(data.size()));
    queue.enqueueReadBuffer(buffer, CL_TRUE, 0, data.size() * sizeof(int), data.data());
    return data;
}

DeviceInfo fake(const std::string& id, const std::string& name, const std::string& type,
                const std::string& vendor = "Vendor", const std::string& platform = "Platform") {
    DeviceInfo d;
    d.id = id;
    d.name = name;
    d.type = type;
    d.vendor = vendor;
    d.platform = platform;
    return d;
}

}  // namespace

// ---- no device needed ----------------------------------------------------------

TEST_CASE("cl_error_name names every OpenCL error code", "[opencl]") {
    CHECK(std::string(cl_error_name(CL_SUCCESS)) == "CL_SUCCESS");
    CHECK(std::string(cl_error_name(CL_INVALID_VALUE)) == "CL_INVALID_VALUE");
    CHECK(std::string(cl_error_name(CL_INVALID_BUFFER_SIZE)) == "CL_INVALID_BUFFER_SIZE");
    CHECK(std::string(cl_error_name(CL_BUILD_PROGRAM_FAILURE)) == "CL_BUILD_PROGRAM_FAILURE");
    CHECK(std::string(cl_error_name(CL_INVALID_DEVICE_PARTITION_COUNT)) == "CL_INVALID_DEVICE_PARTITION_COUNT");
    CHECK(std::string(cl_error_name(-69)) == "CL_INVALID_PIPE_SIZE");
    CHECK(std::string(cl_error_name(-72)) == "CL_MAX_SIZE_RESTRICTION_EXCEEDED");
    CHECK(std::string(cl_error_name(-1001)) == "CL_PLATFORM_NOT_FOUND_KHR");
    CHECK(std::string(cl_error_name(12345)) == "CL_UNKNOWN_ERROR(12345)");
    CHECK(std::string(cl_error_name(-20)) == "CL_UNKNOWN_ERROR(-20)");
    // Every core code from 0 to -72 that exists has a name.
    for (cl_int code : {0, -1, -5, -11, -19, -30, -45, -61, -68, -70, -71}) {
        CHECK_FALSE(contains(cl_error_name(code), "UNKNOWN"));
    }
}

TEST_CASE("OpenCL failures become kdrt::Error(Device)", "[opencl]") {
    try {
        throw_cl_error(CL_OUT_OF_RESOURCES, "launching trace");
        FAIL("throw_cl_error returned");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Device);
        CHECK(std::string(e.what()) == "launching trace: CL_OUT_OF_RESOURCES");
    }

    const Error converted = to_kdrt_error(cl::Error(CL_INVALID_BUFFER_SIZE, "clCreateBuffer"), "allocating nodes");
    CHECK(converted.code() == ErrorCode::Device);
    CHECK(std::string(converted.what()) == "allocating nodes: clCreateBuffer failed: CL_INVALID_BUFFER_SIZE");

    CHECK(guard_cl("nothing", [] { return 42; }) == 42);
    try {
        guard_cl("reading the image", []() -> int { throw cl::Error(CL_INVALID_MEM_OBJECT, "clEnqueueReadBuffer"); });
        FAIL("guard_cl let the cl::Error through");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Device);
        CHECK(contains(e.what(), "reading the image"));
        CHECK(contains(e.what(), "CL_INVALID_MEM_OBJECT"));
    }
}

TEST_CASE("SHA-256 matches the FIPS 180-4 test vectors", "[opencl]") {
    CHECK(to_hex(sha256("")) == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    CHECK(to_hex(sha256("abc")) == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    CHECK(to_hex(sha256("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq")) ==
          "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    const std::string million(1000000, 'a');
    CHECK(to_hex(sha256(million)) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");

    // Fed in uneven pieces, across block boundaries, the digest is the same.
    Sha256 pieces;
    std::size_t offset = 0;
    for (std::size_t step = 1; offset < million.size(); step = step * 3 % 1000 + 1) {
        const std::size_t n = std::min(step, million.size() - offset);
        pieces.update(million.data() + offset, n);
        offset += n;
    }
    CHECK(pieces.finish() == sha256(million));
    // 55, 56 and 64 bytes: the padding edge cases.
    CHECK(to_hex(sha256(std::string(55, 'a'))) == "9f4390f8d30c2dd92ec9f095b65e2b9ae9b0a925a5258e241c9f1e910f734318");
    CHECK(to_hex(sha256(std::string(56, 'a'))) == "b35439a4ac6f0948b6d6f9e3c6af0f5f590ce20f1bde7090ef7970686ec6738a");
    CHECK(to_hex(sha256(std::string(64, 'a'))) == "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb");
}

TEST_CASE("assemble_kernel_source puts the shared headers first, with #line markers", "[opencl]") {
    REQUIRE(kEmbeddedClFileCount >= 3);
    const std::string source = assemble_kernel_source();
    // The public layout, then the kernels' private records, which include it.
    const std::string headers[] = {"libkdrt/include/kdrt/layout.h", "libkdrt/src/device/kernel_records.h"};
    CHECK(std::string(kEmbeddedClFiles[0].name) == headers[0]);
    CHECK(std::string(kEmbeddedClFiles[1].name) == headers[1]);

    const std::string layout = read_text(fs::path(KDRT_SOURCE_DIR) / headers[0]);
    REQUIRE_FALSE(layout.empty());
    const std::string first_marker = "#line 1 \"" + headers[0] + "\"\n";
    REQUIRE(source.rfind(first_marker, 0) == 0);
    CHECK(source.compare(first_marker.size(), layout.size(), layout) == 0);

    // Every file is embedded byte for byte and marked, in order.
    std::size_t previous = 0;
    for (std::size_t i = 0; i < kEmbeddedClFileCount; ++i) {
        const std::string name = kEmbeddedClFiles[i].name;
        INFO(name);
        CHECK(read_text(fs::path(KDRT_SOURCE_DIR) / name) == kEmbeddedClFiles[i].text);
        const std::size_t at = source.find("#line 1 \"" + name + "\"\n");
        REQUIRE(at != std::string::npos);
        CHECK(at >= previous);
        previous = at;
        if (i > 1) CHECK(fs::path(name).extension() == ".cl");
    }
    CHECK(contains(source, "#line 1 \"cl/common.cl\""));
    CHECK(contains(source, "#line 1 \"cl/render.cl\""));
    // The records' include of the layout is blanked: the source needs no include path.
    const std::string records = read_text(fs::path(KDRT_SOURCE_DIR) / headers[1]);
    REQUIRE(contains(records, "#include <kdrt/layout.h>"));
    CHECK_FALSE(contains(source, "#include <kdrt/layout.h>"));
}

TEST_CASE("assemble_kernel_source blanks includes of the embedded headers, keeping line numbers", "[opencl]") {
    const EmbeddedClFile files[] = {
        {"include/kdrt/layout.h", "#define LAYOUT 1\n"},
        {"src/device/kernel_records.h", "#include <kdrt/layout.h>\n#define RECORDS 1\n"},
        {"cl/a.cl",
         "#include \"layout.h\"\n"
         "  #  include <kdrt/layout.h>\r\n"
         "#include \"../libkdrt/src/device/kernel_records.h\"\n"
         "#include \"not_layout.h\"\n"
         "#include \"kdrt/layout.hpp\"\n"
         "#include \"a.cl\"\n"
         "int a;"},
    };
    const std::string source = assemble_kernel_source(files);
    CHECK(source ==
          "#line 1 \"include/kdrt/layout.h\"\n"
          "#define LAYOUT 1\n"
          "#line 1 \"src/device/kernel_records.h\"\n"
          "\n"
          "#define RECORDS 1\n"
          "#line 1 \"cl/a.cl\"\n"
          "\n"
          "\n"
          "\n"
          "#include \"not_layout.h\"\n"
          "#include \"kdrt/layout.hpp\"\n"
          "#include \"a.cl\"\n"
          "int a;\n");
}

TEST_CASE("select_device_index follows the spec rules", "[opencl]") {
    const std::vector<DeviceInfo> devices = {
        fake("opencl:0", "pthread-skylake", "cpu", "GenuineIntel", "Portable Computing Language"),
        fake("opencl:1", "Some Accelerator", "accelerator", "Acme", "Acme OpenCL"),
        fake("opencl:2", "NVIDIA H100 80GB HBM3", "gpu", "NVIDIA Corporation", "NVIDIA CUDA"),
    };
    CHECK(select_device_index("opencl", devices) == 2);  // GPU first
    CHECK(select_device_index("OpenCL", devices) == 2);
    CHECK(select_device_index("opencl:0", devices) == 0);
    CHECK(select_device_index("opencl:2", devices) == 2);
    CHECK(select_device_index("opencl:cpu", devices) == 0);
    CHECK(select_device_index("opencl:gpu", devices) == 2);
    CHECK(select_device_index("opencl:accelerator", devices) == 1);
    CHECK(select_device_index("opencl:h100", devices) == 2);    // name
    CHECK(select_device_index("opencl:ACME", devices) == 1);    // vendor
    CHECK(select_device_index("opencl:portable", devices) == 0);  // platform

    const std::vector<DeviceInfo> cpu_only = {fake("opencl:0", "a cpu", "cpu")};
    CHECK(select_device_index("opencl", cpu_only) == 0);
    const std::vector<DeviceInfo> other_only = {fake("opencl:0", "a thing", "custom")};
    CHECK(select_device_index("opencl", other_only) == 0);
    const std::vector<DeviceInfo> accelerator_then_cpu = {fake("opencl:0", "acc", "accelerator"),
                                                          fake("opencl:1", "host", "cpu")};
    CHECK(select_device_index("opencl", accelerator_then_cpu) == 1);

    for (const char* bad : {"opencl:3", "opencl:99999999999999999999", "opencl:nosuch", "opencl:", "cuda",
                            "openclx", "cpu"}) {
        INFO(bad);
        try {
            select_device_index(bad, devices);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            const std::string message = e.what();
            CHECK(contains(message, std::string("'") + bad + "'"));
            CHECK(contains(message, "opencl:2"));
            CHECK(contains(message, "NVIDIA H100 80GB HBM3"));
        }
    }
    CHECK_THROWS_WITH(select_device_index("opencl:gpu", cpu_only), Catch::Contains("no device of type gpu"));
    CHECK_THROWS_WITH(select_device_index("opencl", {}), Catch::Contains("no OpenCL platform was found"));
}

TEST_CASE("check_allocation and check_total refuse what does not fit", "[opencl]") {
    ClDevice device;
    device.info = fake("opencl:7", "Tiny Device", "gpu");
    device.info.max_allocation = 256ull << 20;
    device.info.global_memory = 1024ull << 20;
    CHECK_NOTHROW(check_allocation(device, device.info.max_allocation, "the node buffer"));
    CHECK_NOTHROW(check_allocation(device, 0, "the node buffer"));
    try {
        check_allocation(device, device.info.max_allocation + 1, "the node buffer");
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Device);
        const std::string message = e.what();
        CHECK(contains(message, "the node buffer needs 256.00 MiB (268435457 bytes)"));
        CHECK(contains(message, "the device's largest allocation is 256.00 MiB (268435456 bytes)"));
        CHECK(contains(message, "Tiny Device"));
    }
    CHECK_NOTHROW(check_total(device, device.info.global_memory));
    CHECK_THROWS_AS(check_total(device, device.info.global_memory + 1), Error);
    CHECK_THROWS_WITH(check_total(device, 2048ull << 20), Catch::Contains("1024.00 MiB"));
}

TEST_CASE("ProgramCache picks its directory from the environment", "[opencl]") {
#ifndef _WIN32
    TempDir dir;
    const char* saved = std::getenv("KDRT_KERNEL_CACHE");
    const std::string saved_value = saved != nullptr ? saved : "";

    ::setenv("KDRT_KERNEL_CACHE", (dir.path / "sub" / "kernels").string().c_str(), 1);
    auto chosen = ProgramCache::default_directory();
    REQUIRE(chosen.has_value());
    CHECK(*chosen == dir.path / "sub" / "kernels");
    CHECK(fs::is_directory(*chosen));

    ::setenv("KDRT_KERNEL_CACHE", "", 1);
    CHECK_FALSE(ProgramCache::default_directory().has_value());
    CHECK_FALSE(ProgramCache(std::nullopt).directory().has_value());

    if (saved != nullptr) {
        ::setenv("KDRT_KERNEL_CACHE", saved_value.c_str(), 1);
    } else {
        ::unsetenv("KDRT_KERNEL_CACHE");
    }
#endif
    CHECK_FALSE(ProgramCache(fs::path()).directory().has_value());
    CHECK(ProgramCache::full_options("-DKDRT_X=1") == "-cl-std=CL1.2 -DKDRT_X=1");
    CHECK(ProgramCache::full_options("") == "-cl-std=CL1.2");
}

// ---- OpenCL devices --------------------------------------------------------------

TEST_CASE("every enumerated OpenCL device has sane info", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const DeviceInfo& info = devices[i].info;
        INFO(info.id << " " << info.name);
        CHECK(info.id == "opencl:" + std::to_string(i));
        CHECK_FALSE(info.platform.empty());
        CHECK_FALSE(info.name.empty());
        CHECK_FALSE(info.vendor.empty());
        CHECK((info.type == "cpu" || info.type == "gpu" || info.type == "accelerator" || info.type == "custom"));
        CHECK_FALSE(info.driver_version.empty());
        CHECK(info.compute_units >= 1);
        CHECK(info.global_memory > 0);
        CHECK(info.max_allocation > 0);
        CHECK(info.max_allocation <= info.global_memory);
        CHECK(devices[i].device() != nullptr);
        CHECK(devices[i].platform() != nullptr);
    }

    // list_devices(): the C++ reference, then the same OpenCL devices.
    const std::vector<DeviceInfo> listed = list_devices();
    REQUIRE(listed.size() == devices.size() + 1);
    CHECK(listed[0].id == "cpu");
    for (std::size_t i = 0; i < devices.size(); ++i) {
        CHECK(listed[i + 1].id == devices[i].info.id);
        CHECK(listed[i + 1].name == devices[i].info.name);
    }
}

TEST_CASE("select_device finds devices by index, type and name", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;

    const ClDevice first = select_device("opencl");
    const bool any_gpu = std::any_of(devices.begin(), devices.end(), [](const ClDevice& d) { return d.info.type == "gpu"; });
    CHECK(first.info.type == (any_gpu ? "gpu" : devices[0].info.type == "cpu" ? "cpu" : first.info.type));
    CHECK(select_device("opencl:0").info.id == "opencl:0");
    CHECK(select_device("opencl:" + std::to_string(devices.size() - 1)).info.id == devices.back().info.id);

    for (const char* type : {"cpu", "gpu"}) {
        auto it = std::find_if(devices.begin(), devices.end(), [&](const ClDevice& d) { return d.info.type == type; });
        if (it != devices.end()) CHECK(select_device(std::string("opencl:") + type).info.id == it->info.id);
    }

    // A substring of the first device's name (PoCL: "pthread-..."), in upper case.
    std::string part = devices[0].info.name.substr(0, std::min<std::size_t>(7, devices[0].info.name.size()));
    std::transform(part.begin(), part.end(), part.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    CHECK(select_device("opencl:" + part).info.id == "opencl:0");
    const bool pocl = std::any_of(devices.begin(), devices.end(),
                                  [](const ClDevice& d) { return contains(d.info.platform, "Portable Computing"); });
    if (pocl) CHECK(select_device("opencl:portable computing").info.platform == "Portable Computing Language");
    // PoCL before 4.0 names its CPU device "pthread-...", later ones "cpu-...".
    if (std::any_of(devices.begin(), devices.end(), [](const ClDevice& d) { return contains(d.info.name, "pthread"); }))
        CHECK(contains(select_device("opencl:pthread").info.name, "pthread"));

    for (const std::string& bad : {std::string("opencl:99"), std::string("opencl:nosuchdevice"), std::string("cuda")}) {
        INFO(bad);
        try {
            select_device(bad);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            const std::string message = e.what();
            CHECK(contains(message, "'" + bad + "'"));
            for (const ClDevice& d : devices) {
                CHECK(contains(message, d.info.id));
                CHECK(contains(message, d.info.name));
            }
        }
    }
}

// The driver's compiler prints its diagnostics to the user's terminal ("1
// warning generated." under PoCL), so the kernels build without any: the
// BVH's and the kd-tree's code for CPU devices, in float and in double where
// the device has fp64. A probe option makes each build a new one, past the
// driver's own cache, which would hold no log.
TEST_CASE("The kernels build on the first OpenCL device without warnings", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    const ClDevice& device = devices[0];
    const cl::Context context(device.device);
    const ProgramCache cache{fs::path()};  // no disk cache
    const std::string source = assemble_kernel_source();
    std::random_device random;
    for (const Accel accel : {Accel::Bvh, Accel::KdTree})
        for (const Precision precision : {Precision::Float, Precision::Double}) {
            if (precision == Precision::Double && !device.info.fp64) continue;
            detail::KernelVariant v;
            v.features = SceneFeatures::all(15);
            v.accel = accel;
            v.fp64 = device.info.fp64;
            v.precision = precision;
            v.cpu_device = detail::cpu_kernels(device);
            v.mailbox = accel == Accel::KdTree;
            v.packed_leaves = v.cpu_device;
            const std::string options =
                detail::kernel_options(v) + " -DKDRT_TEST_BUILD_PROBE=" + std::to_string(random());
            INFO(options);
            const BuiltProgram built = cache.build(context, device, source, options);
            INFO(built.build_log);
            CHECK_FALSE(built.cache_hit);
            CHECK(built.build_log.find("warning") == std::string::npos);
        }
}

TEST_CASE("ProgramCache builds, caches, and rebuilds bad entries", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    const ClDevice& device = devices[0];
    const cl::Context context(device.device);
    TempDir dir;
    const ProgramCache cache(dir.path / "kernels");
    REQUIRE(cache.directory().has_value());
    const std::string options = "-DKDRT_TEST_OPTION=1";
    const std::vector<int> expected = {2, 3, 4, 5};

    const BuiltProgram built = cache.build(context, device, kTinyKernel, options);
    CHECK_FALSE(built.cache_hit);
    CHECK(built.compile_ms > 0.0);
    REQUIRE_FALSE(built.cache_file.empty());
    const fs::path file = built.cache_file;
    REQUIRE(fs::exists(file));
    CHECK(file.parent_path() == *cache.directory());
    CHECK(run_add_one(context, device, built.program) == expected);
    const Sha256Digest key = ProgramCache::key(device, kTinyKernel, ProgramCache::full_options(options));
    CHECK(file.filename() == to_hex(key) + ".clbin");
    const std::optional<std::vector<unsigned char>> binary = read_cache_file(file, key);
    REQUIRE(binary.has_value());
    CHECK_FALSE(binary->empty());
    // No temporary files are left behind: the entry and the cache's secret.
    CHECK(std::distance(fs::directory_iterator(*cache.directory()), fs::directory_iterator()) == 2);
    CHECK((fs::status(*cache.directory()).permissions() & fs::perms::all) == fs::perms::owner_all);
    CHECK((fs::status(file).permissions() & fs::perms::all) ==
          (fs::perms::owner_read | fs::perms::owner_write));

    SECTION("the second build loads the cached binary") {
        const BuiltProgram again = cache.build(context, device, kTinyKernel, options);
        CHECK(again.cache_hit);
        CHECK(again.cache_file == built.cache_file);
        CHECK(run_add_one(context, device, again.program) == expected);
        // A different option set or source is a different entry.
        const BuiltProgram other = cache.build(context, device, kTinyKernel, "-DKDRT_TEST_OPTION=2");
        CHECK_FALSE(other.cache_hit);
        CHECK(other.cache_file != built.cache_file);
        CHECK_FALSE(cache.build(context, device, std::string(kTinyKernel) + "\n", options).cache_hit);
    }

    auto check_rebuilt = [&] {
        const BuiltProgram rebuilt = cache.build(context, device, kTinyKernel, options);
        CHECK_FALSE(rebuilt.cache_hit);
        CHECK(rebuilt.cache_file == built.cache_file);
        CHECK(run_add_one(context, device, rebuilt.program) == expected);
        CHECK(read_cache_file(file, key).has_value());  // rewritten, valid
        CHECK(cache.build(context, device, kTinyKernel, options).cache_hit);
    };

    SECTION("a flipped byte in the binary is caught by the checksum") {
        std::vector<unsigned char> bytes = read_bytes(file);
        bytes[kCacheHeaderBytes + binary->size() / 2] ^= 0x5a;
        write_bytes(file, bytes);
        CHECK_FALSE(read_cache_file(file, key).has_value());
        check_rebuilt();
    }
    SECTION("an altered binary with a recomputed SHA-256 is refused before the driver sees it") {
        std::vector<unsigned char> bytes = read_bytes(file);
        std::vector<unsigned char> altered(bytes.begin() + kCacheHeaderBytes, bytes.end() - 32);
        for (std::size_t i = 8; i < 64 && i < altered.size(); ++i) altered[i] = 0xff;  // past PoCL's magic
        const Sha256Digest digest = sha256(altered.data(), altered.size());
        std::copy(altered.begin(), altered.end(), bytes.begin() + kCacheHeaderBytes);
        std::copy(digest.begin(), digest.end(), bytes.end() - 32);
        write_bytes(file, bytes);
        CHECK_FALSE(read_cache_file(file, key).has_value());
        check_rebuilt();
    }
    SECTION("an entry whose loading process died is evicted, not loaded again") {
        // What a driver crash on a damaged binary leaves: the marker with a dead pid.
        const pid_t child = ::fork();
        if (child == 0) ::_exit(0);
        REQUIRE(child > 0);
        ::waitpid(child, nullptr, 0);
        std::ofstream(file.string() + ".loading") << child;
        check_rebuilt();
        CHECK_FALSE(fs::exists(file.string() + ".loading"));
    }
    SECTION("a FIFO as an entry's loading marker is a warning, never a wait for a writer") {
        REQUIRE(::mkfifo((file.string() + ".loading").c_str(), 0600) == 0);
        const BuiltProgram around = cache.build(context, device, kTinyKernel, options);
        CHECK_FALSE(around.cache_hit);
        CHECK(run_add_one(context, device, around.program) == expected);
        CHECK_THAT(around.cache_warning, Catch::Matchers::Contains(".clbin.loading is not a regular file"));
    }
    SECTION("a FIFO as the cache's secret is a warning, never a wait for a writer") {
        const fs::path secret = *cache.directory() / kSecretFileName;
        fs::remove(secret);
        REQUIRE(::mkfifo(secret.c_str(), 0600) == 0);
        CHECK_FALSE(read_cache_file(file, key).has_value());
        const BuiltProgram rebuilt = cache.build(context, device, kTinyKernel, options);
        CHECK_FALSE(rebuilt.cache_hit);
        CHECK(run_add_one(context, device, rebuilt.program) == expected);
        CHECK_THAT(rebuilt.cache_warning, Catch::Matchers::Contains("cache-secret"));
    }
    SECTION("a FIFO in place of an entry is not opened") {
        fs::remove(file);
        REQUIRE(::mkfifo(file.c_str(), 0600) == 0);
        CHECK_FALSE(read_cache_file(file, key).has_value());
        check_rebuilt();
    }
    SECTION("an entry another live process is loading is left alone and compiled around") {
        std::ofstream(file.string() + ".loading") << ::getppid();
        const BuiltProgram around = cache.build(context, device, kTinyKernel, options);
        CHECK_FALSE(around.cache_hit);
        CHECK(run_add_one(context, device, around.program) == expected);
        CHECK(read_cache_file(file, key).has_value());
        fs::remove(file.string() + ".loading");
        CHECK(cache.build(context, device, kTinyKernel, options).cache_hit);
    }
    SECTION("an entry owned by another user is not loaded") {
        if (::geteuid() != 0) {
            WARN("not root: cannot give the entry away, skipped");
            return;
        }
        REQUIRE(::chown(file.c_str(), 65534, 65534) == 0);
        check_rebuilt();
        struct stat st {};
        REQUIRE(::stat(file.c_str(), &st) == 0);
        CHECK(st.st_uid == ::geteuid());
    }
    SECTION("a symlink in place of an entry is not followed") {
        const fs::path elsewhere = dir.path / "elsewhere.clbin";
        fs::rename(file, elsewhere);
        fs::create_symlink(elsewhere, file);
        check_rebuilt();
        CHECK_FALSE(fs::is_symlink(file));
    }
    SECTION("a truncated file is rebuilt") {
        fs::resize_file(file, fs::file_size(file) / 2);
        check_rebuilt();
    }
    SECTION("a file cut inside the header is rebuilt") {
        fs::resize_file(file, 10);
        check_rebuilt();
    }
    SECTION("a wrong magic is rebuilt") {
        std::vector<unsigned char> bytes = read_bytes(file);
        bytes[0] = 'X';
        write_bytes(file, bytes);
        check_rebuilt();
    }
    SECTION("an entry written for another key is rebuilt") {
        REQUIRE(write_cache_file(file, sha256("another key"), *binary));
        check_rebuilt();
    }
    SECTION("a well-formed entry whose binary the driver refuses falls back to the source") {
        REQUIRE(write_cache_file(file, key, std::vector<unsigned char>(1000, 0xab)));
        REQUIRE(read_cache_file(file, key).has_value());
        check_rebuilt();
    }
}

TEST_CASE("ProgramCache refuses a directory others can write, and says why", "[opencl]") {
    TempDir dir;
    const fs::path shared = dir.path / "shared";
    fs::create_directories(shared);
    fs::permissions(shared, fs::perms::all);
    const ProgramCache cache(shared);
    CHECK_FALSE(cache.directory().has_value());
    CHECK(contains(cache.problem(), shared.string()));
    CHECK(contains(cache.problem(), "writable by other users"));
    const ProgramCache nested(dir.path / "a" / "b");
    REQUIRE(nested.directory().has_value());
    CHECK((fs::status(dir.path / "a").permissions() & fs::perms::all) == fs::perms::owner_all);
    CHECK(nested.problem().empty());
}

TEST_CASE("HMAC-SHA-256 matches RFC 4231", "[opencl]") {
    Sha256Digest key{};
    std::fill(key.begin(), key.begin() + 20, 0x0b);  // test case 1: a 20-byte key, zero-padded like any short key
    CHECK(to_hex(hmac_sha256(key, "Hi There", 8)) ==
          "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
}

TEST_CASE("ProgramCache works without a disk cache", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    const cl::Context context(devices[0].device);
    const ProgramCache cache{fs::path()};
    const BuiltProgram built = cache.build(context, devices[0], kTinyKernel, "");
    CHECK_FALSE(built.cache_hit);
    CHECK(built.cache_file.empty());
    CHECK(run_add_one(context, devices[0], built.program) == std::vector<int>{2, 3, 4, 5});
}

TEST_CASE("a kernel that does not compile throws ClBuildError with the log", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    const cl::Context context(devices[0].device);
    TempDir dir;
    const ProgramCache cache(dir.path);
    const std::string broken =
        "__kernel void broken(__global int* x) {\n"
        "    x[0] = 1\n"  // line 2: missing ';'
        "}\n";
    try {
        cache.build(context, devices[0], broken, "-DKDRT_BROKEN_TEST=1");
        FAIL("the broken kernel built");
    } catch (const ClBuildError& e) {
        CHECK(e.code() == ErrorCode::Device);
        INFO(e.log());
        CHECK(contains(e.log(), "error"));
        CHECK(contains(e.log(), ":2:"));
        CHECK(e.options() == "-cl-std=CL1.2 -DKDRT_BROKEN_TEST=1");
        const std::string message = e.what();
        CHECK(contains(message, e.log()));
        CHECK(contains(message, "-DKDRT_BROKEN_TEST=1"));
        CHECK(contains(message, "CL_BUILD_PROGRAM_FAILURE"));
    }
    // Nothing was cached.
    CHECK(fs::is_empty(dir.path));
}

TEST_CASE("the device's real limits are enforced", "[opencl]") {
    const std::vector<ClDevice> devices = devices_or_warn();
    if (devices.empty()) return;
    for (const ClDevice& device : devices) {
        CHECK_NOTHROW(check_allocation(device, device.info.max_allocation, "the triangle buffer"));
        CHECK_THROWS_WITH(check_allocation(device, device.info.max_allocation + 1, "the triangle buffer"),
                          Catch::Contains("the triangle buffer needs") &&
                              Catch::Contains("the device's largest allocation is"));
        CHECK_THROWS_AS(check_total(device, device.info.global_memory + 1), Error);
    }
}
