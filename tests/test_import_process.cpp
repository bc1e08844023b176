// ImportIsolation::ChildProcess (src/scene/import_process.h): the model comes
// back from the kdrt-import helper exactly as an import in this process
// makes it, and whatever becomes of the helper (a crash, an abort, a hang, an
// exhausted memory limit, garbage on its output, a cancel) is an Error naming
// the file, never the end of this process. Stand-in helpers (shell scripts
// named by $KDRT_IMPORT_HELPER) play the failing importer.
#include "scene/model_wire.h"
#include "temp_dir.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

#ifdef __SANITIZE_ADDRESS__
#define KDRT_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KDRT_TEST_ASAN 1
#endif
#endif

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kdrt::ErrorCode;

namespace {

const fs::path kModels = fs::path(KDRT_TEST_DATA_DIR) / "models";

struct TempDir : kdrt::test::TempDir {
    TempDir() : kdrt::test::TempDir("kdrt-test-import-process") {}
    // An executable shell script standing in for kdrt-import.
    fs::path helper(const std::string& name, const std::string& body) const {
        const fs::path p = write(name, "#!/bin/sh\n" + body + "\n");
        ::chmod(p.c_str(), 0755);
        return p;
    }
};

// Sets $KDRT_IMPORT_HELPER for the scope.
struct HelperOverride {
    explicit HelperOverride(const fs::path& helper) { ::setenv("KDRT_IMPORT_HELPER", helper.c_str(), 1); }
    ~HelperOverride() { ::unsetenv("KDRT_IMPORT_HELPER"); }
    HelperOverride(const HelperOverride&) = delete;
    HelperOverride& operator=(const HelperOverride&) = delete;
};

kdrt::Error import_error(const fs::path& path, const kdrt::ImportOptions& options = {}) {
    try {
        kdrt::import_model(path, kdrt::kIdentityTransform, options);
    } catch (const kdrt::Error& e) {
        return e;
    }
    FAIL("no error importing " << path);
    return kdrt::Error(ErrorCode::InvalidScene, "");
}

void check_same(const kdrt::ImportedModel& a, const kdrt::ImportedModel& b) {
    REQUIRE(a.mesh.positions.size() == b.mesh.positions.size());
    CHECK(a.mesh.positions == b.mesh.positions);
    CHECK(a.mesh.normals == b.mesh.normals);
    REQUIRE(a.mesh.triangles.size() == b.mesh.triangles.size());
    for (std::size_t i = 0; i < a.mesh.triangles.size(); ++i) {
        CHECK(a.mesh.triangles[i].v == b.mesh.triangles[i].v);
        CHECK(a.mesh.triangles[i].n == b.mesh.triangles[i].n);
        CHECK(a.mesh.triangles[i].material == b.mesh.triangles[i].material);
    }
    REQUIRE(a.materials.size() == b.materials.size());
    for (std::size_t i = 0; i < a.materials.size(); ++i) {
        CHECK(a.materials[i].name == b.materials[i].name);
        CHECK(a.materials[i].color == b.materials[i].color);
        CHECK(a.materials[i].shininess == b.materials[i].shininess);
        CHECK(a.materials[i].transmit == b.materials[i].transmit);
    }
    REQUIRE(a.cameras.size() == b.cameras.size());
    for (std::size_t i = 0; i < a.cameras.size(); ++i) {
        CHECK(a.cameras[i].name == b.cameras[i].name);
        CHECK(a.cameras[i].camera.position == b.cameras[i].camera.position);
        CHECK(a.cameras[i].camera.look_at == b.cameras[i].camera.look_at);
        CHECK(a.cameras[i].camera.fov_y == b.cameras[i].camera.fov_y);
        CHECK(a.cameras[i].aspect == b.cameras[i].aspect);
    }
    REQUIRE(a.lights.size() == b.lights.size());
    for (std::size_t i = 0; i < a.lights.size(); ++i) CHECK(a.lights[i].position == b.lights[i].position);
    CHECK(a.bounds.lo == b.bounds.lo);
    CHECK(a.bounds.hi == b.bounds.hi);
    CHECK(a.stats.triangles == b.stats.triangles);
    CHECK(a.stats.meshes == b.stats.meshes);
    CHECK(a.stats.warnings == b.stats.warnings);
}

}  // namespace

TEST_CASE("import process: the helper's model is the model imported in this process", "[import]") {
    kdrt::ImportOptions here;
    here.isolation = kdrt::ImportIsolation::InProcess;
    const std::array<double, 16> moved{2, 0, 0, 1, 0, 1, 0.5, -3, 0, 0, 1, 0.25, 0, 0, 0, 1};
    for (const fs::path& p : {kModels / "scene.gltf", kModels / "room.obj"}) {
        INFO(p);
        check_same(kdrt::import_model(p, moved), kdrt::import_model(p, moved, here));
    }
}

TEST_CASE("import process: a helper that crashes, aborts, hangs or babbles is an error naming the file", "[import]") {
    TempDir dir;
    const fs::path model = kModels / "room.obj";
    SECTION("a crash") {
        HelperOverride h(dir.helper("crash", "kill -SEGV $$"));
        const kdrt::Error e = import_error(model);
        CHECK(e.code() == ErrorCode::InvalidScene);
        CHECK_THAT(e.what(), Contains("room.obj: the importer (Assimp) crashed on this file (SIGSEGV"));
    }
    SECTION("an abort, with what it printed") {
        HelperOverride h(dir.helper("abort", "echo 'Assertion `index < size` failed.' >&2; kill -ABRT $$"));
        const kdrt::Error e = import_error(model);
        CHECK_THAT(e.what(), Contains("room.obj: the importer (Assimp) aborted on this file (SIGABRT)") &&
                                 Contains("Assertion `index < size` failed."));
    }
    SECTION("a hang, past the time limit") {
        HelperOverride h(dir.helper("hang", "exec sleep 30"));
        kdrt::ImportOptions o;
        o.time_limit_s = 1;
        const auto start = std::chrono::steady_clock::now();
        const kdrt::Error e = import_error(model, o);
        CHECK(e.code() == ErrorCode::ResourceLimit);
        CHECK_THAT(e.what(), Contains("room.obj: the import took longer than 1 s"));
        CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(10));
    }
    SECTION("a cancel") {
        HelperOverride h(dir.helper("hang", "exec sleep 30"));
        kdrt::ImportOptions o;
        int polls = 0;
        o.keep_going = [&] { return ++polls < 3; };
        const kdrt::Error e = import_error(model, o);
        CHECK(e.code() == ErrorCode::Cancelled);
        CHECK(polls == 3);
    }
    SECTION("garbage on its output, and an exit without a result") {
        HelperOverride h(dir.helper("garbage", "printf 'KDRTIMPT%040d' 7"));
        CHECK_THAT(import_error(model).what(), Contains("room.obj: import result:"));
        HelperOverride quiet(dir.helper("quiet", "echo 'no such option' >&2; exit 3"));
        CHECK_THAT(import_error(model).what(),
                   Contains("room.obj: the import helper ended without a result (exit status 3): no such option"));
    }
    SECTION("no helper") {
        HelperOverride h(dir.path / "not-installed");
        const kdrt::Error e = import_error(model);
        CHECK(e.code() == ErrorCode::Unsupported);
        CHECK_THAT(e.what(), Contains("kdrt-import is not installed") && Contains("KDRT_IMPORT_HELPER") &&
                                 Contains("InProcess"));
    }
}

TEST_CASE("import process: the memory limit is the helper's, and its end is an error", "[import]") {
#ifdef KDRT_TEST_ASAN
    WARN("AddressSanitizer's shadow memory leaves no room for an address-space limit: skipped");
    return;
#endif
    TempDir dir;
    // 300,000 triangles of text: Assimp needs some hundreds of megabytes, more than 64 MiB of address space allows.
    std::string obj;
    for (int i = 0; i < 300000; ++i) obj += "v " + std::to_string(i) + " 0 0\n";
    for (int i = 1; i + 2 <= 300000; ++i) obj += "f " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
    const fs::path big = dir.write("big.obj", obj);
    kdrt::ImportOptions o;
    o.memory_limit = std::uint64_t{64} << 20;
    const kdrt::Error e = import_error(big, o);
    CHECK(e.code() == ErrorCode::ResourceLimit);
    CHECK_THAT(e.what(), Contains("big.obj: out of memory") && Contains("the import's memory limit is 64 MiB"));
    CHECK(kdrt::import_model(big).stats.triangles == 299998);  // within the default limit
}

TEST_CASE("import process: damaged result bytes are refused", "[import]") {
    kdrt::ImportOptions here;
    here.isolation = kdrt::ImportIsolation::InProcess;
    std::vector<std::uint8_t> bytes = kdrt::detail::encode_import_result(kdrt::import_model(kModels / "scene.gltf", kdrt::kIdentityTransform, here));
    CHECK(kdrt::detail::decode_import_result(bytes.data(), bytes.size(), "x").stats.triangles > 0);
    for (std::size_t at : {std::size_t{0}, std::size_t{10}, std::size_t{30}, bytes.size() / 2, bytes.size() - 1}) {
        std::vector<std::uint8_t> damaged = bytes;
        damaged[at] ^= 0x40;
        CHECK_THROWS_AS(kdrt::detail::decode_import_result(damaged.data(), damaged.size(), "x"), kdrt::Error);
    }
    CHECK_THROWS_AS(kdrt::detail::decode_import_result(bytes.data(), bytes.size() - 1, "x"), kdrt::Error);
    const std::vector<std::uint8_t> error = kdrt::detail::encode_import_error(ErrorCode::Io, "m.obj: gone");
    try {
        kdrt::detail::decode_import_result(error.data(), error.size(), "x");
        FAIL("an error record decoded as a model");
    } catch (const kdrt::Error& e) {
        CHECK(e.code() == ErrorCode::Io);
        CHECK(std::string(e.what()) == "m.obj: gone");
    }
}
