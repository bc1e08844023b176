// Scene loading: the study's scenes, FORMAT.md's strictness rules, OBJ meshes
// and the programmatic Scene API.
#include <catch2/catch.hpp>
#include "temp_dir.h"

#include "scene/parse_obj_mesh.h"

#include <kdrt/error.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <glm/geometric.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using kdrt::ErrorCode;

namespace {

const fs::path kScenes = KDRT_SCENES_DIR;
const fs::path kData = KDRT_TEST_DATA_DIR;

// A small valid scene; every malformed case below changes exactly one thing.
const std::string kBase = R"({
  "format": "kdrt-scene/1",
  "name": "base",
  "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45 },
  "settings": { "width": 64, "height": 48, "max_depth": 5, "samples": 1,
                "background": [0, 0, 0], "ambient": [0.1, 0.1, 0.1] },
  "materials": {
    "red": { "color": [1, 0, 0], "reflect": 0.2, "shininess": 10 },
    "glass": { "transmit": 0.9, "ior": 1.5 }
  },
  "lights": [ { "position": [0, 5, -5], "color": [1, 1, 1] } ],
  "spheres": [ { "center": [0, 0, 0], "radius": 1, "material": "red" } ],
  "triangles": [ { "v": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "material": "glass" } ],
  "meshes": [ { "obj": "ok.obj", "material": "red" } ]
})";

// kBase with `from` replaced by `to` (which must occur exactly once).
std::string with(const std::string& from, const std::string& to) {
    std::size_t at = kBase.find(from);
    REQUIRE(at != std::string::npos);
    REQUIRE(kBase.find(from, at + 1) == std::string::npos);
    std::string s = kBase;
    s.replace(at, from.size(), to);
    return s;
}

bool near(const glm::dvec3& a, const glm::dvec3& b, double eps = 1e-12) {
    return glm::length(a - b) <= eps;
}

struct TempDir : kdrt::test::TempDir {
    TempDir() : kdrt::test::TempDir("kdrt-test-scene-loader") {}
};

const std::string kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

struct BadCase {
    std::string what;  // what the case breaks (shown on failure)
    std::string json;
    ErrorCode code;
    std::vector<std::string> needles;  // place and a word of the problem
};

}  // namespace

TEST_CASE("the study's scenes load with their counts and values", "[scene]") {
    SECTION("2x2x4") {
        kdrt::Scene s = kdrt::load_scene(kScenes / "2x2x4.json");
        CHECK(s.name == "2x2x4");
        CHECK(s.spheres.size() == 16);
        CHECK(s.materials.size() == 4);
        CHECK(s.object_count() == 16);
        CHECK(s.triangle_count() == 0);
        CHECK(near(s.camera.position, {4.0, 5.5, -5.0}));
        CHECK(s.camera.fov_y == 40.0);
        CHECK(s.settings.width == 500);
        CHECK(s.settings.max_depth == 15);
        CHECK(near(s.settings.background, {0.05, 0.05, 0.12}));
        CHECK(near(s.spheres[0].center, {-0.5, -0.5, -1.5}));
        CHECK(s.spheres[0].radius == 0.45);
        CHECK(s.materials[s.spheres[0].material].name == "ball0");
        CHECK(s.materials[s.spheres[15].material].name == "ball3");
        const kdrt::Material& ball0 = s.materials[s.material_id("ball0")];
        CHECK(near(ball0.color, {0.9, 0.2, 0.2}));
        CHECK(ball0.diffuse == 0.8);
        CHECK(ball0.specular == 0.5);
        CHECK(ball0.shininess == 40.0);
        CHECK(ball0.reflect == 0.3);
        CHECK(ball0.transmit == 0.0);  // defaults
        CHECK(ball0.ior == 1.5);
        REQUIRE(s.lights.size() == 1);
        CHECK(near(s.lights[0].position, {5, 8, -6}));
    }
    SECTION("ball-o-calypse") {
        kdrt::Scene s = kdrt::load_scene(kScenes / "ball-o-calypse.json");
        CHECK(s.spheres.size() == 8000);
        CHECK(s.materials.size() == 125);
        CHECK(s.materials.front().name == "m000");  // file order
        CHECK(s.materials.back().name == "m444");
        CHECK(near(s.spheres.back().center, {9.5, 9.5, 9.5}));
        CHECK(s.materials[s.spheres.back().material].name == "m444");
    }
    SECTION("insane") {
        kdrt::Scene s = kdrt::load_scene(kScenes / "insane.json");
        CHECK(s.spheres.size() == 2);
        CHECK(s.triangles.size() == 24);
        CHECK(s.meshes.empty());
        CHECK(s.object_count() == 26);
        const kdrt::MeshTriangle& t = s.triangles.triangles[0];
        CHECK(near(s.triangles.positions[t.v[0]], {-1, -1, 1}));
        CHECK(near(s.triangles.positions[t.v[1]], {1, -1, 1}));
        CHECK(near(s.triangles.positions[t.v[2]], {1, 1, 1}));
        CHECK(s.materials[t.material].name == "white");
        CHECK(t.n[0] == kdrt::kNoNormal);
        CHECK(s.materials[s.spheres[0].material].name == "mirror");
        CHECK(s.spheres[1].radius == 0.25);
    }
    SECTION("lens") {
        kdrt::Scene s = kdrt::load_scene(kScenes / "lens.json");
        CHECK(s.name == "lens");
        CHECK(s.spheres.size() == 3);
        const kdrt::Material& glass = s.materials[s.spheres[2].material];
        CHECK(glass.name == "glass");
        CHECK(glass.transmit == 0.9);
        CHECK(glass.ior == 1.5);
        CHECK(glass.reflect == 0.1);
        CHECK(s.spheres[2].radius == 0.9);
    }
    SECTION("purple-wall") {
        kdrt::Scene s = kdrt::load_scene(kScenes / "purple-wall.json");
        CHECK(s.spheres.empty());
        CHECK(s.triangles.size() == 2048);
        CHECK(s.object_count() == 2048);
        CHECK(s.materials.size() == 2);
        const kdrt::MeshTriangle& last = s.triangles.triangles.back();
        CHECK(s.materials[last.material].name == "red");
        CHECK(near(s.triangles.positions[last.v[1]], {4.0, 4.0, 0.0}));
    }
}

TEST_CASE("malformed scenes are rejected with file, place and problem", "[scene]") {
    TempDir dir;
    dir.write("ok.obj", kTriangleObj);
    dir.write("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n");
    dir.write("zero-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 3\n");
    dir.write("two-corners.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n");
    dir.write("no-faces.obj", "# only vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");

    const std::string mesh = R"("meshes": [ { "obj": "ok.obj", "material": "red" } ])";
    const std::string mesh_with = R"("meshes": [ { "obj": "ok.obj", "material": "red", "transform": )";
    const auto transform = [&](const std::string& numbers) {
        return with(mesh, mesh_with + "[" + numbers + "] } ]");
    };
    const auto obj = [&](const std::string& file) {
        return with(R"("obj": "ok.obj")", "\"obj\": \"" + file + "\"");
    };
    const ErrorCode bad = ErrorCode::InvalidScene;

    const std::vector<BadCase> cases = {
        // document and format
        {"missing format", with(R"("format": "kdrt-scene/1",)", ""), bad, {"format", "missing"}},
        {"wrong format", with("kdrt-scene/1", "kdrt-scene/2"), bad, {"format", "kdrt-scene/2", "unsupported"}},
        {"format not a string", with(R"("kdrt-scene/1")", "1"), bad, {"format", "string"}},
        {"unknown top-level key", with(R"("name": "base",)", R"("name": "base", "colour": 1,)"), bad,
         {"colour", "unknown key"}},
        {"top level not an object", "[1, 2, 3]", bad, {"expected an object", "array"}},
        {"JSON syntax error", with(R"("radius": 1,)", R"("radius": 1,,)"), bad, {"line 12", "syntax error"}},
        {"empty document", "", bad, {"line 1", "syntax error"}},
        {"1e999", with(R"("radius": 1)", R"("radius": 1e999)"), bad, {"spheres[0].radius", "finite"}},
        {"duplicate key", with(R"("radius": 1)", R"("radius": 1, "radius": 2)"), bad,
         {"spheres[0].radius", "duplicate"}},
        // types and vectors
        {"string for a number", with(R"("radius": 1)", R"("radius": "1")"), bad,
         {"spheres[0].radius", "expected a number", "string"}},
        {"vector of 2", with(R"("center": [0, 0, 0])", R"("center": [0, 0])"), bad,
         {"spheres[0].center", "3 numbers", "2 elements"}},
        {"vector with a string", with(R"("up": [0, 1, 0])", R"("up": [0, "1", 0])"), bad,
         {"camera.up[1]", "expected a number"}},
        {"vector of 4", with(R"("ambient": [0.1, 0.1, 0.1])", R"("ambient": [0.1, 0.1, 0.1, 1])"), bad,
         {"settings.ambient", "3 numbers"}},
        {"boolean for a number", with(R"("fov_y": 45)", R"("fov_y": true)"), bad, {"camera.fov_y", "boolean"}},
        {"triangle of 2 points", with(R"([[0, 0, 0], [1, 0, 0], [0, 1, 0]])", R"([[0, 0, 0], [1, 0, 0]])"), bad,
         {"triangles[0].v", "3 points"}},
        {"spheres not an array", with(R"("spheres": [ { "center": [0, 0, 0], "radius": 1, "material": "red" } ],)",
                                      R"("spheres": {},)"),
         bad, {"spheres", "expected an array"}},
        {"material not an object", with(R"("glass": { "transmit": 0.9, "ior": 1.5 })", R"("glass": 0.9)"), bad,
         {"materials.glass", "expected an object"}},
        {"name not a string", with(R"("name": "base")", R"("name": 7)"), bad, {"name", "expected a string"}},
        // unknown and missing keys
        {"unknown material key", with(R"("reflect": 0.2)", R"("refelct": 0.2)"), bad,
         {"materials.red.refelct", "unknown key"}},
        {"unknown sphere key", with(R"("radius": 1)", R"("radius": 1, "radious": 1)"), bad,
         {"spheres[0].radious", "unknown key"}},
        {"missing camera", with(R"("camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45 },)", ""),
         bad, {"camera", "missing"}},
        {"light without color", with(R"(, "color": [1, 1, 1] })", " }"), bad, {"lights[0].color", "missing"}},
        {"mesh without obj", with(R"("obj": "ok.obj", )", ""), bad, {"meshes[0].obj", "missing"}},
        {"mesh with obj and model", with(R"("obj": "ok.obj", )", R"("obj": "ok.obj", "model": "ok.obj", )"), bad,
         {"meshes[0]", "both"}},
        // ranges
        {"negative radius", with(R"("radius": 1)", R"("radius": -1)"), bad, {"spheres[0].radius", "> 0"}},
        {"fov 180", with(R"("fov_y": 45)", R"("fov_y": 180)"), bad, {"camera.fov_y", "(0, 180)"}},
        {"fov 0", with(R"("fov_y": 45)", R"("fov_y": 0)"), bad, {"camera.fov_y", "(0, 180)"}},
        {"width 0", with(R"("width": 64)", R"("width": 0)"), bad, {"settings.width", "[1, 16384]"}},
        {"height 16385", with(R"("height": 48)", R"("height": 16385)"), bad, {"settings.height", "[1, 16384]"}},
        {"width 1.5", with(R"("width": 64)", R"("width": 1.5)"), bad, {"settings.width", "integer"}},
        {"width 1e10", with(R"("width": 64)", R"("width": 1e10)"), bad, {"settings.width", "out of range"}},
        {"samples 0", with(R"("samples": 1)", R"("samples": 0)"), bad, {"settings.samples", ">= 1"}},
        {"max_depth 0", with(R"("max_depth": 5)", R"("max_depth": 0)"), bad, {"settings.max_depth", "[1, 64]"}},
        {"max_depth 65", with(R"("max_depth": 5)", R"("max_depth": 65)"), bad, {"settings.max_depth", "[1, 64]"}},
        {"reflect 1.5", with(R"("reflect": 0.2)", R"("reflect": 1.5)"), bad, {"materials.red.reflect", "[0, 1]"}},
        {"transmit -0.1", with(R"("transmit": 0.9)", R"("transmit": -0.1)"), bad,
         {"materials.glass.transmit", "[0, 1]"}},
        {"ior 0", with(R"("ior": 1.5)", R"("ior": 0)"), bad, {"materials.glass.ior", "> 0"}},
        {"shininess 0", with(R"("shininess": 10)", R"("shininess": 0)"), bad, {"materials.red.shininess", "> 0"}},
        {"look_at == position", with(R"("look_at": [0, 0, 0])", R"("look_at": [0, 0, -5])"), bad,
         {"camera.look_at", "differ"}},
        {"up parallel to view", with(R"("up": [0, 1, 0])", R"("up": [0, 0, 2])"), bad, {"camera.up", "parallel"}},
        // material references
        {"undefined material", with(R"("material": "glass")", R"("material": "blue")"), bad,
         {"triangles[0].material", "undefined material", "blue"}},
        {"material reference not a string", with(R"("radius": 1, "material": "red")", R"("radius": 1, "material": 0)"),
         bad, {"spheres[0].material", "expected a string"}},
        // meshes
        {"missing OBJ", obj("missing.obj"), ErrorCode::Io, {"meshes[0].obj", "missing.obj", "cannot open"}},
        {"OBJ with bad index", obj("bad-index.obj"), bad, {"meshes[0].obj", "bad-index.obj:5", "out of range"}},
        {"OBJ with index 0", obj("zero-index.obj"), bad, {"meshes[0].obj", "zero-index.obj:4", "cannot parse"}},
        {"OBJ face of 2 corners", obj("two-corners.obj"), bad, {"meshes[0].obj", "two-corners.obj:5", "at least 3"}},
        {"OBJ without faces", obj("no-faces.obj"), bad, {"meshes[0].obj", "no faces"}},
        {"transform of 15 numbers", transform("1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0"), bad,
         {"meshes[0].transform", "16 numbers", "15 elements"}},
        {"transform not affine", transform("1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1"), bad,
         {"meshes[0].transform", "affine"}},
        {"transform singular", transform("1,0,0,0, 0,1,0,0, 1,1,0,0, 0,0,0,1"), bad,
         {"meshes[0].transform", "singular"}},
        {"transform with a string", transform("1,0,0,0, 0,1,0,0, 0,0,1,\"0\", 0,0,0,1"), bad,
         {"meshes[0].transform[11]", "expected a number"}},
    };

    // The base itself must be valid, or every case would pass for the wrong reason.
    kdrt::Scene ok = kdrt::parse_scene(kBase, dir.path, "base.json");
    CHECK(ok.object_count() == 3);
    CHECK(cases.size() >= 18);

    for (const BadCase& c : cases) {
        INFO("case: " << c.what);
        try {
            kdrt::parse_scene(c.json, dir.path, "base.json");
            FAIL_CHECK("accepted: " << c.what);
        } catch (const kdrt::Error& e) {
            INFO("message: " << e.what());
            CHECK(e.code() == c.code);
            CHECK_THAT(e.what(), StartsWith("base.json: "));
            for (const std::string& needle : c.needles) CHECK_THAT(e.what(), Contains(needle));
        }
    }
}

TEST_CASE("load_scene names the file and resolves OBJ paths next to it", "[scene]") {
    TempDir dir;
    SECTION("a missing scene file is an I/O error") {
        fs::path missing = dir.path / "nope.json";
        try {
            kdrt::load_scene(missing);
            FAIL("accepted a missing file");
        } catch (const kdrt::Error& e) {
            CHECK(e.code() == ErrorCode::Io);
            CHECK_THAT(e.what(), Contains(missing.string()));
        }
    }
    SECTION("errors start with the scene path") {
        fs::path p = dir.write("bad.json", with(R"("radius": 1)", R"("radius": 0)"));
        dir.write("ok.obj", kTriangleObj);
        try {
            kdrt::load_scene(p);
            FAIL("accepted radius 0");
        } catch (const kdrt::Error& e) {
            CHECK(e.code() == ErrorCode::InvalidScene);
            CHECK_THAT(e.what(), StartsWith(p.string() + ": spheres[0].radius: "));
        }
    }
    SECTION("meshes, ids and the transform from a scene file") {
        kdrt::Scene s = kdrt::load_scene(kData / "fan_scene.json");
        CHECK(s.settings.width == 500);  // settings absent: defaults
        CHECK(s.settings.samples == 1);
        REQUIRE(s.meshes.size() == 2);
        // 1 sphere, 1 loose triangle, fan.obj: quad (2) + pentagon (3) + triangle (1),
        // normals.obj: 4 triangles.
        CHECK(s.meshes[0].size() == 6);
        CHECK(s.meshes[1].size() == 4);
        CHECK(s.object_count() == 1 + 1 + 6 + 4);
        CHECK(s.materials[s.meshes[0].triangles[0].material].name == "white");
        CHECK(s.materials[s.meshes[1].triangles[0].material].name == "grey");
        // normals.obj was scaled by 2 in x and moved by (1, 2, 3).
        CHECK(near(s.meshes[1].positions[1], {3, 2, 3}));
    }
}

TEST_CASE("OBJ polygons are fanned in face order", "[scene]") {
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    kdrt::Mesh m = kdrt::load_obj_mesh(kData / "fan.obj", identity, 7);
    REQUIRE(m.positions.size() == 5);
    CHECK(m.normals.empty());
    using V = std::array<std::uint32_t, 3>;
    const std::vector<V> expected = {
        {0, 1, 2}, {0, 2, 3},             // quad 1 2 3 4
        {0, 1, 2}, {0, 2, 3}, {0, 3, 4},  // pentagon 1 2 3 4 5
        {4, 3, 2},                        // triangle 5 4 3, in group "second"
    };
    REQUIRE(m.triangles.size() == expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        INFO("triangle " << i);
        CHECK(m.triangles[i].v == expected[i]);
        CHECK(m.triangles[i].n[0] == kdrt::kNoNormal);
        CHECK(m.triangles[i].material == 7);
    }
}

TEST_CASE("OBJ normals: per-corner indices and the inverse transpose", "[scene]") {
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    using V = std::array<std::uint32_t, 3>;
    const V none{kdrt::kNoNormal, kdrt::kNoNormal, kdrt::kNoNormal};

    SECTION("indices are picked up, partial faces get none") {
        kdrt::Mesh m = kdrt::load_obj_mesh(kData / "normals.obj", identity, 0);
        REQUIRE(m.triangles.size() == 4);
        REQUIRE(m.normals.size() == 3);
        CHECK(m.triangles[0].n == V{0, 1, 2});
        CHECK(m.triangles[1].n == V{2, 1, 0});  // v/vt/vn
        CHECK(m.triangles[2].n == none);        // 1//1 2 3: only one corner has a normal
        CHECK(m.triangles[3].n == none);
        CHECK(m.triangles[3].v == V{0, 1, 2});  // -3 -2 -1
        CHECK(near(m.normals[0], {0, 0, 1}));
        CHECK(near(m.normals[1], {0, 0.6, 0.8}));
        CHECK(near(m.normals[2], {std::sqrt(0.5), std::sqrt(0.5), 0}));  // renormalised
    }
    SECTION("non-uniform scale and translation") {
        // x scaled by 2, then moved by (1, 2, 3).
        const std::array<double, 16> t{2, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1};
        kdrt::Mesh m = kdrt::load_obj_mesh(kData / "normals.obj", t, 0);
        CHECK(near(m.positions[0], {1, 2, 3}));
        CHECK(near(m.positions[1], {3, 2, 3}));
        CHECK(near(m.positions[2], {1, 3, 3}));
        // (1, 1, 0) through the inverse transpose diag(1/2, 1, 1): (1/2, 1, 0), normalised.
        CHECK(near(m.normals[2], glm::dvec3{1, 2, 0} / std::sqrt(5.0)));
        CHECK(near(m.normals[0], {0, 0, 1}));
        // A transformed normal stays perpendicular to the transformed surface:
        // the plane x + y = 1 becomes x/2 + y = const.
        CHECK(std::abs(glm::dot(m.normals[2], glm::dvec3{2, -1, 0})) < 1e-12);
    }
    SECTION("a rotation keeps normals unit and rotated") {
        // 90 degrees about z: (x, y, z) -> (-y, x, z).
        const std::array<double, 16> t{0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        kdrt::Mesh m = kdrt::load_obj_mesh(kData / "normals.obj", t, 0);
        CHECK(near(m.normals[1], {-0.6, 0, 0.8}));
        CHECK(near(m.positions[1], {0, 1, 0}));
    }
}

TEST_CASE("load_obj_mesh errors name the OBJ file", "[scene]") {
    TempDir dir;
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const auto expect = [&](const fs::path& p, ErrorCode code, const std::string& needle) {
        try {
            kdrt::load_obj_mesh(p, identity, 0);
            FAIL_CHECK("accepted " << p);
        } catch (const kdrt::Error& e) {
            INFO(e.what());
            CHECK(e.code() == code);
            CHECK_THAT(e.what(), Contains(p.string()));
            CHECK_THAT(e.what(), Contains(needle));
        }
    };
    expect(dir.path / "missing.obj", ErrorCode::Io, "cannot open");
    expect(dir.write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n"), ErrorCode::InvalidScene,
           ":5: normal index out of range");
    expect(dir.write("z.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n"), ErrorCode::InvalidScene,
           ":4: vertex normal has zero length");
    expect(dir.write("r.obj", "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 -4\r\n"), ErrorCode::InvalidScene,
           ":4: vertex index out of range");
}

TEST_CASE("an OBJ read in several pieces loads as its text parses", "[scene]") {
    // Files of many megabytes are read by parallel tasks, 4 MiB apiece
    // (read_input_bytes): over 8 MiB here, three pieces, with lines across their seams.
    TempDir dir;
    std::string text;
    const int n = 260000;
    for (int i = 0; i < n; ++i) text += "v " + std::to_string(i) + ".25 " + std::to_string(i % 977) + " -3.5e-1\n";
    for (int i = 1; i + 2 <= n; i += 2)
        text += "f " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
    REQUIRE(text.size() > (std::size_t{8} << 20));
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const kdrt::Mesh loaded = kdrt::load_obj_mesh(dir.write("big.obj", text), identity, 0);
    const kdrt::Mesh parsed = kdrt::detail::parse_obj_mesh(text, "big.obj", identity, 0);
    REQUIRE(loaded.positions.size() == static_cast<std::size_t>(n));
    CHECK(loaded.positions == parsed.positions);
    CHECK(loaded.positions[n - 1] == glm::dvec3(n - 1 + 0.25, (n - 1) % 977, -0.35));
    REQUIRE(loaded.triangles.size() == parsed.triangles.size());
    bool same = true;
    for (std::size_t i = 0; i < loaded.triangles.size(); ++i) same &= loaded.triangles[i].v == parsed.triangles[i].v;
    CHECK(same);
}

TEST_CASE("the programmatic Scene API gives FORMAT.md ids", "[scene]") {
    kdrt::Scene s;
    kdrt::Material red;
    red.name = "red";
    red.color = {1, 0, 0};
    CHECK(s.add_material(red) == 0);
    CHECK(s.add_material(kdrt::Material{}) == 1);
    CHECK(s.materials[1].name == "material1");
    CHECK(s.add_light({{0, 5, 0}, {1, 1, 1}}) == 0);

    CHECK(s.add_sphere({0, 0, 0}, 1.0, 0) == 0);
    CHECK(s.add_sphere({3, 0, 0}, 0.5, 1) == 1);
    CHECK(s.add_triangle({0, 0, 2}, {1, 0, 2}, {0, 1, 2}, 1) == 2);
    CHECK(s.add_triangle({0, 0, 3}, {1, 0, 3}, {0, 1, 3}, 0) == 3);

    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    kdrt::Mesh fan = kdrt::load_obj_mesh(kData / "fan.obj", identity, 0);
    CHECK(s.add_mesh(fan) == 4);
    CHECK(s.add_mesh(fan) == 4 + 6);
    CHECK(s.object_count() == 16);
    CHECK(s.triangle_count() == 14);
    CHECK(s.material_id("red") == 0);
    CHECK_THROWS_AS(s.material_id("blue"), kdrt::Error);
    CHECK_NOTHROW(kdrt::validate(s));

    s.spheres[1].material = 5;
    CHECK_THROWS_WITH(kdrt::validate(s), Contains("spheres[1].material"));
}

// ---- robustness: special files, strict OBJ, JSON limits, printable messages ----

namespace {

const std::array<double, 16> kIdentity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// The kdrt::Error a call throws; fails the test when it throws nothing.
template <typename F>
kdrt::Error error_of(F&& f) {
    try {
        f();
    } catch (const kdrt::Error& e) {
        return e;
    }
    FAIL("accepted");
    return kdrt::Error(ErrorCode::InvalidScene, "");
}

bool has_control_character(const std::string& s) {
    for (unsigned char c : s)
        if (c < 0x20 || c == 0x7F) return true;
    return false;
}

}  // namespace

TEST_CASE("scene and OBJ inputs must be regular files", "[scene]") {
    TempDir dir;
    const fs::path fifo = dir.path / "fifo";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    // The FIFO has no writer: reading it would block forever.
    SECTION("a FIFO as the scene") {
        kdrt::Error e = error_of([&] { kdrt::load_scene(fifo); });
        CHECK(e.code() == ErrorCode::Io);
        CHECK_THAT(e.what(), Contains(fifo.string()) && Contains("not a regular file"));
    }
    SECTION("a FIFO as a mesh, directly and from a scene") {
        kdrt::Error e = error_of([&] { kdrt::load_obj_mesh(fifo, kIdentity, 0); });
        CHECK(e.code() == ErrorCode::Io);
        CHECK_THAT(e.what(), Contains(fifo.string()) && Contains("not a regular file"));
        const std::string json = with(R"("obj": "ok.obj")", R"("obj": "fifo")");
        kdrt::Error s = error_of([&] { kdrt::parse_scene(json, dir.path, "base.json"); });
        CHECK(s.code() == ErrorCode::Io);
        CHECK_THAT(s.what(), Contains("meshes[0].obj") && Contains(fifo.string()) && Contains("not a regular file"));
    }
    SECTION("/dev/zero as the scene and as a mesh") {
        kdrt::Error e = error_of([&] { kdrt::load_scene("/dev/zero"); });
        CHECK(e.code() == ErrorCode::Io);
        CHECK_THAT(e.what(), Contains("/dev/zero") && Contains("not a regular file"));
        kdrt::Error m = error_of([&] { kdrt::load_obj_mesh("/dev/zero", kIdentity, 0); });
        CHECK(m.code() == ErrorCode::Io);
        CHECK_THAT(m.what(), Contains("/dev/zero") && Contains("not a regular file"));
    }
    SECTION("a directory as the scene and as a mesh") {
        kdrt::Error e = error_of([&] { kdrt::load_scene(dir.path); });
        CHECK(e.code() == ErrorCode::Io);
        CHECK_THAT(e.what(), Contains(dir.path.string()) && Contains("directory"));
        kdrt::Error m = error_of([&] { kdrt::load_obj_mesh(dir.path, kIdentity, 0); });
        CHECK(m.code() == ErrorCode::Io);
        CHECK_THAT(m.what(), Contains("directory"));
    }
}

TEST_CASE("the OBJ loader rejects what it cannot represent, naming file, line and problem", "[scene]") {
    TempDir dir;
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    struct ObjCase {
        std::string what, text, line, problem;
    };
    const std::vector<ObjCase> cases = {
        {"NaN coordinate", "v nan 0 3\n" + tri + "f 1 2 3\n", ":1:", "not finite"},
        {"infinite coordinate", tri + "v inf 0 3\nf 1 2 3\n", ":4:", "not finite"},
        {"letters for coordinates", "v a b c\n" + tri + "f 2 3 4\n", ":1:", "not a number"},
        {"two coordinates", tri + "v 1 2\nf 1 2 3\n", ":4:", "missing vertex coordinate 3"},
        {"a coordinate too large for a double", tri + "v 1e999 0 0\nf 1 2 3\n", ":4:", "out of the range"},
        {"stray token after a vertex", tri + "v 1 2 3 x\nf 1 2 3\n", ":4:", "3 coordinates"},
        {"stray token after a normal", tri + "vn 0 0 1 1\nf 1 2 3\n", ":4:", "unexpected \"1\""},
        {"index past 2^32 that would wrap", tri + "f 1 2 4294967299\n", ":4:", "vertex index out of range"},
        {"index past 2^64", tri + "f 1 2 99999999999999999999\n", ":4:", "vertex index out of range"},
        {"relative normal index before the first normal", tri + "vn 0 0 1\nf 1//-2 2//-1 3//-1\n", ":5:",
         "normal index out of range"},
        {"NaN normal", tri + "vn nan 0 1\nf 1//1 2//1 3//1\n", ":4:", "not finite"},
        {"zero-length normal", tri + "vn 0 0 0\nf 1//1 2//1 3//1\n", ":4:", "zero length"},
        {"garbage in an index", tri + "f 1 2 3x\n", ":4:", "cannot parse vertex index"},
        {"empty normal index", tri + "f 1// 2// 3//\n", ":4:", "cannot parse face corner"},
        {"garbage texture index", tri + "f 1/a 2/b 3/c\n", ":4:", "cannot parse texture index"},
        {"not an OBJ file", "this is not an OBJ file\n", ":1:", "unsupported statement \"this\""},
        {"line elements", tri + "l 1 2\nf 1 2 3\n", ":4:", "unsupported statement \"l\""},
        {"face of 2 corners", tri + "f 1 2\n", ":4:", "at least 3"},
        {"index 0", tri + "f 0 1 2\n", ":4:", "start at 1"},
        {"vertex with 4 numbers", tri + "v 1 2 3 1\nf 1 2 3\n", ":4:", "3 coordinates"},
    };
    for (const ObjCase& c : cases) {
        INFO("case: " << c.what);
        const fs::path p = dir.write("case.obj", c.text);
        kdrt::Error e = error_of([&] { kdrt::load_obj_mesh(p, kIdentity, 0); });
        INFO("message: " << e.what());
        CHECK(e.code() == ErrorCode::InvalidScene);
        CHECK_THAT(e.what(), StartsWith(p.string() + c.line));
        CHECK_THAT(e.what(), Contains(c.problem));
    }
}

TEST_CASE("the OBJ loader accepts the documented extras", "[scene]") {
    TempDir dir;
    const fs::path p = dir.write("extras.obj",
                                 "o thing\ns 1\nv +1 0 0 # trailing comment\nv 0 1 0 0.5 0.5 0.5\nv 0 0 1\n"
                                 "vt 0 0\nvp 0.5\n\t v 1e-3 -2.5E2 .5\nf 1/1 2/1 3/1\nf -4 -3 -2 -1\n");
    kdrt::Mesh m = kdrt::load_obj_mesh(p, kIdentity, 3);
    REQUIRE(m.positions.size() == 4);
    CHECK(near(m.positions[0], {1, 0, 0}));
    CHECK(near(m.positions[3], {1e-3, -250, 0.5}));
    using V = std::array<std::uint32_t, 3>;
    REQUIRE(m.triangles.size() == 3);
    CHECK(m.triangles[0].v == V{0, 1, 2});
    CHECK(m.triangles[1].v == V{0, 1, 2});
    CHECK(m.triangles[2].v == V{0, 2, 3});
}

TEST_CASE("a large OBJ parses in pieces to the same mesh and the right line numbers", "[scene]") {
    // About 2 MB: more than one parallel chunk. Each face uses relative
    // indices, so a chunk must know how many vertices came before it.
    TempDir dir;
    const int n = 40000;
    std::ostringstream relative, absolute;
    for (int i = 0; i < n; ++i) {
        const std::string v = "v " + std::to_string(i) + " " + std::to_string(i % 7) + " 0.5\n"
                              "v " + std::to_string(i) + " 1 " + std::to_string(i % 3) + "\n"
                              "v 0 " + std::to_string(i) + " 2\nvn 0 0 1\n";
        relative << v << "f -3//-1 -2//-1 -1//-1\n";
        absolute << v << "f " << 3 * i + 1 << "//" << i + 1 << " " << 3 * i + 2 << "//" << i + 1 << " " << 3 * i + 3
                 << "//" << i + 1 << "\n";
    }
    const kdrt::Mesh a = kdrt::load_obj_mesh(dir.write("rel.obj", relative.str()), kIdentity, 0);
    const kdrt::Mesh b = kdrt::load_obj_mesh(dir.write("abs.obj", absolute.str()), kIdentity, 0);
    REQUIRE(a.triangles.size() == std::size_t(n));
    REQUIRE(b.triangles.size() == std::size_t(n));
    REQUIRE(a.positions.size() == std::size_t(3 * n));
    bool same = true;
    for (std::size_t i = 0; i < a.triangles.size(); ++i) {
        const std::uint32_t k = static_cast<std::uint32_t>(i);
        same = same && a.triangles[i].v == b.triangles[i].v && a.triangles[i].n == b.triangles[i].n &&
               a.triangles[i].v == std::array<std::uint32_t, 3>{3 * k, 3 * k + 1, 3 * k + 2} &&
               a.triangles[i].n[0] == k;
    }
    CHECK(same);
    CHECK(a.positions == b.positions);
    CHECK(near(a.positions.back(), {0, n - 1, 2}));

    // An error far into the file (in a later chunk) names its own line.
    std::string text = relative.str();
    text += "v 1 2\n";
    kdrt::Error e = error_of([&] { kdrt::load_obj_mesh(dir.write("late.obj", text), kIdentity, 0); });
    CHECK_THAT(e.what(), Contains(":" + std::to_string(5 * n + 1) + ": missing vertex coordinate"));
}

TEST_CASE("scene JSON: nesting depth and message length are bounded", "[scene]") {
    SECTION("a 100000-deep unterminated object is refused at depth 64") {
        std::string json = R"({"format": "kdrt-scene/1", "x": )";
        for (int i = 0; i < 100000; ++i) json += R"({"a": )";
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "deep.json"); });
        CHECK(e.code() == ErrorCode::InvalidScene);
        CHECK_THAT(e.what(), StartsWith("deep.json: line 1, column ") && Contains("nested deeper than 64"));
        CHECK(std::string(e.what()).size() < 400);
    }
    SECTION("deep arrays too") {
        const std::string json = std::string(70, '[') + std::string(70, ']');
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "deep.json"); });
        CHECK_THAT(e.what(), Contains("column 65") && Contains("nested deeper than 64"));
    }
    SECTION("a megabyte unterminated string") {
        const std::string json = with(R"("name": "base")", "\"name\": \"" + std::string(1 << 20, 'x'));
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "long.json"); });
        CHECK_THAT(e.what(), Contains("syntax error"));
        CHECK(std::string(e.what()).size() < 400);
    }
    SECTION("a megabyte unknown key") {
        const std::string json = with(R"("name": "base",)", "\"" + std::string(1 << 20, 'k') + "\": 1,");
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "key.json"); });
        CHECK_THAT(e.what(), Contains("unknown key"));
        CHECK(std::string(e.what()).size() < 600);
    }
    SECTION("200000 unknown keys: the first one is named") {
        std::string json = R"({"format": "kdrt-scene/1", )";
        for (int i = 0; i < 200000; ++i) json += "\"unknown" + std::to_string(i) + "\": 0, ";
        json += R"("name": "x"})";
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "keys.json"); });
        CHECK_THAT(e.what(), StartsWith("keys.json: unknown0: unknown key"));
    }
    SECTION("duplicate keys are still found in a large object") {
        std::string json = R"({"format": "kdrt-scene/1", "materials": {)";
        for (int i = 0; i < 20000; ++i) json += "\"m" + std::to_string(i) + "\": {}, ";
        json += R"("m17": {}}})";
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "dup.json"); });
        CHECK_THAT(e.what(), Contains("materials.m17: duplicate key"));
    }
}

TEST_CASE("a large scene parses completely", "[scene]") {
    std::string json = R"({"format": "kdrt-scene/1", "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0],
        "up": [0, 1, 0], "fov_y": 45 }, "materials": {"m": {}}, "spheres": [)";
    const int n = 20000;
    for (int i = 0; i < n; ++i)
    {
        if (i) json += ",";
        json += R"({"center": [)";
        json += std::to_string(i);
        json += R"(, 0, 0], "radius": 0.5, "material": "m"})";
    }
    json += "]}";
    kdrt::Scene s = kdrt::parse_scene(json, ".", "big.json");
    REQUIRE(s.spheres.size() == std::size_t(n));
    CHECK(s.spheres.back().center.x == n - 1);
    // A bad value deep in the array is still placed exactly.
    const std::string bad = json.substr(0, json.rfind("0.5")) + "-1" + json.substr(json.rfind("0.5") + 3);
    kdrt::Error e = error_of([&] { kdrt::parse_scene(bad, ".", "big.json"); });
    CHECK_THAT(e.what(), Contains("spheres[" + std::to_string(n - 1) + "].radius"));
}

TEST_CASE("names echoed in messages are printable", "[scene]") {
    SECTION("an undefined material name with terminal escapes and a newline") {
        const std::string json = with(R"("material": "glass")", R"("material": "\u001b[31mred\nline")");
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "esc.json"); });
        INFO(e.what());
        CHECK_FALSE(has_control_character(e.what()));
        CHECK_THAT(e.what(), Contains("undefined material '\\x1b[31mred\\nline'"));
    }
    SECTION("a material name in a range error") {
        const std::string json = with(R"("glass": { "transmit": 0.9, "ior": 1.5 })",
                                      R"("glass": { "transmit": 0.9, "ior": 1.5 }, "r\u0007ed\r": { "reflect": 2 })");
        TempDir dir;
        dir.write("ok.obj", kTriangleObj);
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, dir.path, "esc.json"); });
        INFO(e.what());
        CHECK_FALSE(has_control_character(e.what()));
        CHECK_THAT(e.what(), Contains("materials.r\\x07ed\\r.reflect"));
    }
    SECTION("an unknown key") {
        const std::string json = with(R"("name": "base",)", R"("name": "base", "\u001b]0;title\u0007": 1,)");
        kdrt::Error e = error_of([&] { kdrt::parse_scene(json, ".", "esc.json"); });
        CHECK_FALSE(has_control_character(e.what()));
        CHECK_THAT(e.what(), Contains("\\x1b]0;title\\x07: unknown key"));
    }
    SECTION("an OBJ line") {
        TempDir dir;
        const fs::path p = dir.write("esc.obj", "v 0 0 \x1b[2J\n");
        kdrt::Error e = error_of([&] { kdrt::load_obj_mesh(p, kIdentity, 0); });
        CHECK_FALSE(has_control_character(e.what()));
        CHECK_THAT(e.what(), Contains("\\x1b[2J"));
    }
}

TEST_CASE("validate rejects zero-length and non-finite mesh normals", "[scene]") {
    kdrt::Scene s;
    s.add_material(kdrt::Material{});
    kdrt::Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 2}};
    kdrt::MeshTriangle t;
    t.v = {0, 1, 2};
    t.n = {0, 1, 0};
    m.triangles = {t};
    s.add_mesh(m);
    CHECK_NOTHROW(kdrt::validate(s));
    s.meshes[0].normals[1] = {0, 0, 0};
    CHECK_THROWS_WITH(kdrt::validate(s), Contains("meshes[0].normals[1]") && Contains("non-zero length"));
    s.meshes[0].normals[1] = {0, NAN, 1};
    CHECK_THROWS_WITH(kdrt::validate(s), Contains("meshes[0].normals[1]") && Contains("finite"));
}
