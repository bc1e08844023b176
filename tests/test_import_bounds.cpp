// What a hostile model file cannot do (docs/IMPORT.md, "Bounds" and
// "Isolation"): overflow the stack or trip an assertion inside Assimp, make
// a small file take gigabytes, take time quadratic in its instances, or read
// files outside its folder. Each case was a crash, an out-of-memory or a
// read of ../secret.bin before these bounds; now each is an Error naming the
// file, in the importer's helper process and in this one alike.
#include "temp_dir.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kdrt::ErrorCode;

namespace {

struct TempDir : kdrt::test::TempDir {
    TempDir() : kdrt::test::TempDir("kdrt-test-import-bounds") {}
};

std::string base64(const std::string& bytes) {
    static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const auto byte = [&](std::size_t i) { return i < bytes.size() ? static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) : 0u; };
    std::string out;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::uint32_t v = byte(i) << 16 | byte(i + 1) << 8 | byte(i + 2);
        const std::size_t present = std::min<std::size_t>(3, bytes.size() - i);
        for (std::size_t k = 0; k < 4; ++k) out += k <= present ? kDigits[(v >> (18 - 6 * k)) & 63] : '=';
    }
    return out;
}

// One triangle: three float positions and three uint16 indices (two bytes of padding).
std::string triangle_buffer() {
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint16_t indices[4] = {0, 1, 2, 0};
    std::string bytes(44, '\0');
    std::memcpy(bytes.data(), positions, 36);
    std::memcpy(bytes.data() + 36, indices, 8);
    return bytes;
}

// A glTF 2.0 file with `nodes` and `scene_nodes` (JSON arrays) around one
// triangle mesh; `buffer_uri` names its buffer (default: a data URI); `extra`
// is more top-level members, with a leading comma.
std::string gltf(const std::string& nodes, const std::string& scene_nodes, const std::string& extra = "",
                 const std::string& buffer_uri = "") {
    const std::string uri = buffer_uri.empty() ? "data:application/octet-stream;base64," + base64(triangle_buffer()) : buffer_uri;
    return R"({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 44, "uri": ")" + uri + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "nodes": )" + nodes + R"(, "scenes": [{"nodes": )" + scene_nodes + R"(}], "scene": 0)" + extra + "}";
}

// n nodes, each the only child of the one before; the last holds the mesh.
std::string chain_of_nodes(std::size_t n) {
    std::string nodes = "[";
    for (std::size_t i = 0; i + 1 < n; ++i) nodes += R"({"children": [)" + std::to_string(i + 1) + "]},";
    return nodes + R"({"mesh": 0}])";
}

// A root with n children that share the one mesh, each moved a little.
std::string instances(std::size_t n) {
    std::string nodes = R"([{"children": [)";
    for (std::size_t i = 1; i <= n; ++i) nodes += std::to_string(i) + (i < n ? "," : "]},");
    for (std::size_t i = 0; i < n; ++i)
        nodes += R"({"mesh": 0, "translation": [)" + std::to_string(i * 0.001) + ",0,0]}" + (i + 1 < n ? "," : "]");
    return nodes;
}

kdrt::ImportOptions in_process() {
    kdrt::ImportOptions o;
    o.isolation = kdrt::ImportIsolation::InProcess;
    return o;
}

// The error of importing `path` with `options`; fails the test when there is none.
kdrt::Error import_error(const fs::path& path, const kdrt::ImportOptions& options = {}) {
    try {
        kdrt::import_model(path, kdrt::kIdentityTransform, options);
    } catch (const kdrt::Error& e) {
        return e;
    }
    FAIL("no error importing " << path);
    return kdrt::Error(ErrorCode::InvalidScene, "");
}

// Both ways of importing refuse the file with a message naming it and saying why.
void check_refused(const fs::path& path, const std::string& why) {
    for (const kdrt::ImportOptions& options : {kdrt::ImportOptions{}, in_process()}) {
        INFO(path << (options.isolation == kdrt::ImportIsolation::InProcess ? " in process" : " in the helper"));
        const kdrt::Error e = import_error(path, options);
        CHECK(e.code() == ErrorCode::InvalidScene);
        CHECK_THAT(e.what(), Contains(path.filename().string()) && Contains(why));
    }
}

std::string le32(std::uint32_t v) {
    std::string s(4, '\0');
    for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(i)] = static_cast<char>(v >> (8 * i));
    return s;
}

// A .glb of `json` and a BIN chunk whose header declares `bin_length` bytes
// while `bin` follows.
std::string glb(const std::string& json, std::uint32_t bin_length, const std::string& bin) {
    std::string padded = json;
    while (padded.size() % 4) padded += ' ';
    const std::string body = le32(static_cast<std::uint32_t>(padded.size())) + "JSON" + padded + le32(bin_length) +
                             std::string("BIN\0", 4) + bin;
    return "glTF" + le32(2) + le32(static_cast<std::uint32_t>(12 + body.size())) + body;
}

// A binary FBX 7.4 file of one top-level record holding one array property.
std::string fbx_with_array(char type, std::uint32_t count, std::uint32_t encoding, const std::string& data) {
    const std::string property = std::string(1, type) + le32(count) + le32(encoding) +
                                 le32(static_cast<std::uint32_t>(data.size())) + data;
    const std::string name = "Vertices";
    const std::size_t start = 27;
    const std::size_t end = start + 13 + name.size() + property.size();
    std::string file = std::string("Kaydara FBX Binary  \0\x1a\0", 23) + le32(7400);
    file += le32(static_cast<std::uint32_t>(end)) + le32(1) + le32(static_cast<std::uint32_t>(property.size())) +
            std::string(1, static_cast<char>(name.size())) + name + property;
    return file + std::string(13, '\0') + std::string(160, '\0');  // the top level's null record, a footer
}

}  // namespace

TEST_CASE("import bounds: what overflowed Assimp's stack or aborted it is refused", "[import]") {
    TempDir dir;
    check_refused(dir.write("deep-nodes.gltf", gltf(chain_of_nodes(100000), "[0]")), "deeper than 512 levels");
    const std::string deep_extras = gltf(R"([{"mesh": 0}])", "[0]", R"(, "extras": )" + std::string(1000000, '[') +
                                                                            std::string(1000000, ']'));
    check_refused(dir.write("deep-json.gltf", deep_extras), "nested deeper than 128 levels");
    const std::string transform =
        R"(, "images": [{"uri": "data:image/png;base64,"}], "textures": [{"source": 0}],
       "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                     "extensions": {"KHR_texture_transform": {"scale": [1]}}}}}])";
    check_refused(dir.write("transform.gltf", gltf(R"([{"mesh": 0}])", "[0]", transform)),
                  "KHR_texture_transform.scale must be an array of 2 numbers");
    // A raw FBX array whose count says more than its bytes (Assimp asserts that they match).
    check_refused(dir.write("raw.fbx", fbx_with_array('d', 1000, 0, std::string(24, '\0'))), "holds 24 bytes");
    // Within the bounds: 500 nested nodes import.
    const kdrt::ImportedModel ok = kdrt::import_model(dir.write("500.gltf", gltf(chain_of_nodes(500), "[0]")));
    CHECK(ok.stats.triangles == 1);
}

TEST_CASE("import bounds: small files that asked for gigabytes are refused before any allocation", "[import]") {
    TempDir dir;
    check_refused(dir.write("chunk.glb", glb(gltf(R"([{"mesh": 0}])", "[0]"), 0xFFFFFFFEu, std::string(44, '\0'))),
                  "GLB chunk of 4294967294 bytes does not fit");
    std::string json_chunk = glb(gltf(R"([{"mesh": 0}])", "[0]"), 44, std::string(44, '\0'));
    json_chunk.replace(12, 4, le32(0xFFFFFFFEu));  // Assimp allocated 4.2 GB for this one
    check_refused(dir.write("json-chunk.glb", json_chunk), "GLB JSON chunk of 4294967294 bytes does not fit");
    // Children shared 21 levels deep: 2^21 copies of the last node.
    std::string dag = "[";
    for (int i = 0; i < 21; ++i) dag += R"({"children": [)" + std::to_string(i + 1) + "," + std::to_string(i + 1) + "]},";
    dag += R"({"mesh": 0}])";
    check_refused(dir.write("dag.gltf", gltf(dag, "[0]")), "expand to more than 1000000 node copies");
    // A face list of 0x20000000 indices in a 200-byte binary PLY.
    const std::string ply = std::string("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                        "property float y\nproperty float z\nelement face 1\n"
                                        "property list uint int vertex_indices\nend_header\n") +
                            std::string(36, '\0') + le32(0x20000000u) + std::string(12, '\0');
    check_refused(dir.write("list.ply", ply), "a list of 536870912 items does not fit");
    // A deflated FBX array of 800 million doubles from 16 bytes.
    check_refused(dir.write("inflate.fbx", fbx_with_array('d', 800000000u, 1, std::string(16, '\0'))),
                  "cannot inflate from 16 bytes");
    // A buffer declaring more bytes than its data URI holds, an accessor beyond its buffer view.
    std::string long_buffer = gltf(R"([{"mesh": 0}])", "[0]");
    long_buffer.replace(long_buffer.find("\"byteLength\": 44"), 16, "\"byteLength\": 4000000000");
    check_refused(dir.write("buffer.gltf", long_buffer), "declares 4000000000 bytes");
    std::string long_accessor = gltf(R"([{"mesh": 0}])", "[0]");
    long_accessor.replace(long_accessor.find("\"count\": 3, \"type\": \"VEC3\""), 10, "\"count\": 300000000");
    check_refused(dir.write("accessor.gltf", long_accessor), "does not fit in its bufferView");
}

// 100,000 nodes sharing one mesh: each instance used to grow the mesh by its
// own size, copying it each time (17-30 s for 20,000 instances, hours for
// these); now the mesh is allocated once. ctest's timeout guards the time.
TEST_CASE("import bounds: instances of a mesh import in time linear in their number", "[import]") {
    TempDir dir;
    const fs::path file = dir.write("instances.gltf", gltf(instances(100000), "[0]"));
    for (const kdrt::ImportOptions& options : {kdrt::ImportOptions{}, in_process()}) {
        const kdrt::ImportedModel m = kdrt::import_model(file, kdrt::kIdentityTransform, options);
        CHECK(m.stats.triangles == 100000);
        CHECK(m.stats.meshes == 100000);
        CHECK(m.mesh.positions.size() == 300000);
        CHECK(m.mesh.positions.capacity() == 300000);  // allocated once, exactly
        CHECK(m.bounds.hi.x == Approx(100.999).margin(0.001));
    }
}

TEST_CASE("import bounds: a model's files are read inside its folder unless allowed", "[import]") {
    TempDir dir;
    fs::create_directories(dir.path / "model" / "sub");
    dir.write("secret.bin", triangle_buffer());
    dir.write("model/sub/inside.bin", triangle_buffer());
    const fs::path outside = dir.write("model/outside.gltf", gltf(R"([{"mesh": 0}])", "[0]", "", "../secret.bin"));
    const fs::path inside = dir.write("model/inside.gltf", gltf(R"([{"mesh": 0}])", "[0]", "", "sub/inside.bin"));
    fs::create_symlink(dir.path / "secret.bin", dir.path / "model" / "link.bin");
    const fs::path linked = dir.write("model/linked.gltf", gltf(R"([{"mesh": 0}])", "[0]", "", "link.bin"));
    const std::string escaped = (dir.path / "model" / "x").string() + "/../../secret.bin";

    for (const fs::path& p : {outside, linked}) {
        INFO(p);
        const kdrt::Error e = import_error(p);
        CHECK_THAT(e.what(), Contains(p.filename().string()) && Contains("outside the model's folder") &&
                                 Contains("allow_outside_files"));
        CHECK(import_error(p, in_process()).code() == ErrorCode::InvalidScene);
    }
    CHECK(kdrt::import_model(inside).stats.triangles == 1);
    kdrt::ImportOptions allow;
    allow.allow_outside_files = true;
    CHECK(kdrt::import_model(outside, kdrt::kIdentityTransform, allow).stats.triangles == 1);
    CHECK(kdrt::import_model(linked, kdrt::kIdentityTransform, allow).stats.triangles == 1);

    // An OBJ's material library outside: a warning that says so, the model renders with default materials.
    dir.write("shared.mtl", "newmtl red\nKd 1 0 0\n");
    const fs::path obj = dir.write("model/tri.obj", "mtllib ../shared.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    const kdrt::ImportedModel m = kdrt::import_model(obj);
    REQUIRE(m.stats.warnings.size() == 2);  // Assimp then looks for tri.mtl beside the model, which is not there
    CHECK_THAT(m.stats.warnings[0], Contains("tri.obj: referenced files not found (tri.mtl)"));
    CHECK_THAT(m.stats.warnings[1], Contains("tri.obj") && Contains("outside the model's folder") && Contains("shared.mtl"));
    CHECK(m.materials.at(0).color.y > 0.5);  // Assimp's grey default, not the library's red
    const kdrt::ImportedModel allowed = kdrt::import_model(obj, kdrt::kIdentityTransform, allow);
    CHECK(allowed.stats.warnings.empty());
    CHECK(allowed.materials.at(0).color == glm::dvec3(1, 0, 0));
}

TEST_CASE("import bounds: a scene passes its import options and collects its models' warnings", "[import]") {
    TempDir dir;
    dir.write("lonely.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
    const fs::path scene = dir.write("scene.json", R"({"format": "kdrt-scene/1",
      "camera": {"position": [0,0,5], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},
      "meshes": [{"model": "lonely.obj"}]})");
    std::vector<std::string> warnings;
    kdrt::SceneLoadOptions options;
    options.warnings = &warnings;
    CHECK(kdrt::load_scene(scene, options).triangle_count() == 1);
    REQUIRE(warnings.size() == 1);
    CHECK_THAT(warnings[0], Contains("scene.json: meshes[0].model: ") && Contains("lonely.obj") && Contains("gone.mtl"));
}

TEST_CASE("import bounds: a NUL in a model's path is named, not cut off", "[import]") {
    const std::string with_nul("models/a\0b.obj", 14);
    const kdrt::Error e = import_error(with_nul);
    CHECK(e.code() == ErrorCode::Io);
    CHECK_THAT(e.what(), Contains("models/a\\x00b.obj") && Contains("NUL"));
    try {
        kdrt::parse_scene(R"({"format": "kdrt-scene/1",
          "camera": {"position": [0,0,5], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},
          "meshes": [{"model": "a\u0000b.obj"}]})", ".", "nul.json");
        FAIL("a NUL in a model path was accepted");
    } catch (const kdrt::Error& error) {
        CHECK_THAT(error.what(), Contains("meshes[0].model") && Contains("a\\x00b.obj") && Contains("NUL"));
    }
}

TEST_CASE("import bounds: a glTF camera's extreme aspect and a field of view of 0 or less", "[import]") {
    TempDir dir;
    const auto with_camera = [&](const std::string& name, const std::string& perspective) {
        return dir.write(name, gltf(R"([{"mesh": 0}, {"camera": 0, "translation": [0.3, 0.3, 3]}])", "[0, 1]",
                                    R"(, "cameras": [{"type": "perspective", "perspective": )" + perspective + "}]"));
    };
    // An aspect of 1e30 overflowed the rounding of the default width (a 1 x 500 image): the widest image instead.
    const fs::path wide = with_camera("wide.gltf", R"({"aspectRatio": 1e30, "yfov": 0.7, "znear": 0.1})");
    kdrt::ModelSceneOptions first;
    const kdrt::Scene s = kdrt::scene_from_model(wide, first);
    CHECK(s.settings.width == 16384);
    CHECK(s.settings.height == 500);
    // yfov 0 or negative is a perspective camera with a bad field of view, not an orthographic one.
    for (const char* yfov : {"0", "-0.5"}) {
        INFO("yfov " << yfov);
        const fs::path flat = with_camera("flat.gltf", std::string(R"({"aspectRatio": 1.5, "yfov": )") + yfov + R"(, "znear": 0.1})");
        const kdrt::ImportedModel m = kdrt::import_model(flat);
        REQUIRE(m.cameras.size() == 1);
        CHECK_FALSE(m.cameras[0].orthographic);
        kdrt::ModelSceneOptions pick;
        pick.camera = 0;
        try {
            kdrt::scene_from_model(flat, pick);
            FAIL("a camera with yfov " << yfov << " was used");
        } catch (const kdrt::Error& e) {
            CHECK_THAT(e.what(), Contains("flat.gltf: camera 0") && Contains("fov_y") && !Contains("orthographic"));
        }
        // Unpicked, it is passed over for the default camera, with a warning saying why.
        kdrt::ImportStats stats;
        const kdrt::Scene d = kdrt::scene_from_model(flat, first, &stats);
        CHECK(d.camera.fov_y == 40.0);
        REQUIRE(stats.warnings.size() == 1);
        CHECK_THAT(stats.warnings[0], Contains("camera 0") && Contains("not used") && Contains("fov_y"));
    }
}
