// Model import (docs/IMPORT.md): OBJ+MTL, glTF 2.0 (text and binary), PLY
// (ASCII and binary) and the other listed formats, written by hand in
// tests/data/models or by Assimp's exporters here; the material rule, the
// cameras and lights, the defaults, mixing with a scene's own objects, the
// same picture on the C++ reference and OpenCL, and malformed files.
#include "have_opencl.h"
#include "opencl/cl_devices.h"
#include "temp_dir.h"
#include "scene/material_mapping.h"

#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/image.h>
#include <kdrt/model_import.h>
#include <kdrt/render.h>

#include <assimp/Exporter.hpp>
#include <assimp/GltfMaterial.h>
#include <assimp/Importer.hpp>
#include <assimp/ObjMaterial.h>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kdrt::ErrorCode;

namespace {

const fs::path kModels = fs::path(KDRT_TEST_DATA_DIR) / "models";
constexpr double kPi = 3.14159265358979323846;

bool near(const glm::dvec3& a, const glm::dvec3& b, double eps = 1e-6) { return glm::length(a - b) <= eps; }

struct TempDir : kdrt::test::TempDir {
    TempDir() : kdrt::test::TempDir("kdrt-test-model-import") {}
};

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// An n x n grid of quads (2 n^2 triangles) on [0, 2] x [0, 1] x [0, 2] with
// up normals and one grey material, built the way an importer would.
std::unique_ptr<aiScene> grid_scene(unsigned n) {
    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = new aiNode("root");
    scene->mRootNode->mNumMeshes = 1;
    scene->mRootNode->mMeshes = new unsigned[1]{0};
    scene->mNumMaterials = 1;
    scene->mMaterials = new aiMaterial*[1]{new aiMaterial};
    const aiColor3D grey(0.7f, 0.7f, 0.7f);
    scene->mMaterials[0]->AddProperty(&grey, 1, AI_MATKEY_COLOR_DIFFUSE);
    aiMesh* mesh = new aiMesh;
    scene->mNumMeshes = 1;
    scene->mMeshes = new aiMesh*[1]{mesh};
    mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    mesh->mMaterialIndex = 0;
    const unsigned side = n + 1;
    mesh->mNumVertices = side * side;
    mesh->mVertices = new aiVector3D[mesh->mNumVertices];
    mesh->mNormals = new aiVector3D[mesh->mNumVertices];
    for (unsigned j = 0; j < side; ++j)
        for (unsigned i = 0; i < side; ++i) {
            const float x = 2.0f * static_cast<float>(i) / static_cast<float>(n);
            const float z = 2.0f * static_cast<float>(j) / static_cast<float>(n);
            const float y = 0.5f + 0.5f * std::sin(3.0f * x) * std::cos(2.0f * z);  // within [0, 1]
            mesh->mVertices[j * side + i] = aiVector3D(x, y, z);
            mesh->mNormals[j * side + i] = aiVector3D(0, 1, 0);
        }
    mesh->mNumFaces = 2 * n * n;
    mesh->mFaces = new aiFace[mesh->mNumFaces];
    unsigned f = 0;
    for (unsigned j = 0; j < n; ++j)
        for (unsigned i = 0; i < n; ++i) {
            const unsigned a = j * side + i, b = a + 1, c = a + side, d = c + 1;
            for (auto tri : {std::array<unsigned, 3>{a, c, b}, std::array<unsigned, 3>{b, c, d}}) {
                aiFace& face = mesh->mFaces[f++];
                face.mNumIndices = 3;
                face.mIndices = new unsigned[3]{tri[0], tri[1], tri[2]};
            }
        }
    return scene;
}

void export_scene(const aiScene& scene, const std::string& format, const fs::path& path) {
    Assimp::Exporter exporter;
    INFO("export " << format << " to " << path);
    REQUIRE(exporter.Export(&scene, format, path.string()) == AI_SUCCESS);
}

void drop_metadata(aiNode* node) {
    delete node->mMetaData;
    node->mMetaData = nullptr;
    for (unsigned i = 0; i < node->mNumChildren; ++i) drop_metadata(node->mChildren[i]);
}

// A model read by Assimp, to be exported in other formats. Its metadata is
// dropped: Assimp 5.2's exporters copy the scene first, and abort on the
// nested metadata its glTF importer makes.
struct ReadBack {
    std::unique_ptr<aiScene> scene;
    explicit ReadBack(const fs::path& p) {
        Assimp::Importer importer;
        REQUIRE(importer.ReadFile(p.string(), 0) != nullptr);
        scene.reset(importer.GetOrphanedScene());
        drop_metadata(scene->mRootNode);
        delete scene->mMetaData;
        scene->mMetaData = nullptr;
    }
};

// scene.gltf and scene.bin packed into one binary glTF (glTF 2.0 spec,
// "GLB File Format Specification"): Assimp's exporter drops cameras and lights.
std::string pack_glb(std::string json, std::string bin) {
    const std::string uri = "\"uri\": \"scene.bin\",";
    const std::size_t at = json.find(uri);
    REQUIRE(at != std::string::npos);
    json.erase(at, uri.size());
    while (json.size() % 4) json += ' ';
    while (bin.size() % 4) bin += '\0';
    std::string out;
    const auto u32 = [&](std::uint32_t v) {
        for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
    };
    out += "glTF";
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
    u32(static_cast<std::uint32_t>(json.size()));
    out += "JSON";
    out += json;
    u32(static_cast<std::uint32_t>(bin.size()));
    out += std::string("BIN\0", 4);
    out += bin;
    return out;
}

// A string literal's bytes, NULs included.
template <std::size_t N>
std::string with_nuls(const char (&bytes)[N]) {
    return std::string(bytes, N - 1);
}

// The error a model import throws, or a failed check when there is none.
kdrt::Error import_error(const fs::path& path) {
    try {
        kdrt::import_model(path);
    } catch (const kdrt::Error& e) {
        return e;
    }
    FAIL("no error importing " << path);
    return kdrt::Error(ErrorCode::InvalidScene, "");
}

using kdrt_test::have_opencl;

// Where a point lands in the camera's picture, FORMAT.md's camera inverted:
// true when it is inside the frame.
bool in_frame(const kdrt::Camera& c, double aspect, const glm::dvec3& p) {
    const glm::dvec3 forward = glm::normalize(c.look_at - c.position);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, c.up));
    const glm::dvec3 up = glm::cross(right, forward);
    const glm::dvec3 d = p - c.position;
    const double z = glm::dot(d, forward);
    if (!(z > 0.0)) return false;
    const double t = std::tan(c.fov_y * kPi / 360.0);
    return std::abs(glm::dot(d, right) / z) <= t * aspect && std::abs(glm::dot(d, up) / z) <= t;
}

}  // namespace

TEST_CASE("import: OBJ+MTL triangles and materials follow the MTL rule", "[import]") {
    const kdrt::ImportedModel m = kdrt::import_model(kModels / "room.obj");
    // floor quad + mirror quad + 6 cube quads, each fanned into 2
    CHECK(m.stats.triangles == 16);
    CHECK(m.mesh.size() == 16);
    CHECK(m.stats.warnings.empty());
    CHECK(m.cameras.empty());
    CHECK(m.lights.empty());
    REQUIRE(m.materials.size() == 3);
    CHECK(near(m.bounds.lo, {-4, 0, -4}));
    CHECK(near(m.bounds.hi, {4, 3, 4}));

    const kdrt::Material& matte = m.materials[0];
    CHECK(matte.name == "room.obj:matte");
    CHECK(near(matte.color, {0.8, 0.6, 0.4}));
    CHECK(matte.diffuse == 1.0);
    CHECK(matte.specular == Approx(0.5));  // luminance of Ks 0.5 0.5 0.5
    CHECK(matte.shininess == Approx(20));
    CHECK(matte.reflect == 0.0);
    CHECK(matte.transmit == 0.0);

    const kdrt::Material& mirror = m.materials[1];
    CHECK(mirror.name == "room.obj:mirror");
    CHECK(mirror.reflect == Approx(0.9));  // illum 3: kr = luminance(Ks)
    CHECK(mirror.shininess == Approx(200));

    const kdrt::Material& glass = m.materials[2];
    CHECK(glass.name == "room.obj:glass");
    CHECK(glass.transmit == Approx(0.8));  // 1 - d
    CHECK(glass.diffuse == Approx(0.2));   // d
    CHECK(glass.ior == Approx(1.45));      // Ni
    CHECK(glass.reflect == Approx(0.2));   // illum 7 reflects, capped at 1 - kt
    CHECK(glass.reflect + glass.transmit <= 1.0 + 1e-12);

    // File order: the floor first, then the mirror with its vertex normals, then the cube.
    const kdrt::MeshTriangle& floor = m.mesh.triangles[0];
    CHECK(floor.material == 0);
    CHECK(floor.n[0] == kdrt::kNoNormal);
    for (auto v : floor.v) CHECK(m.mesh.positions[v].y == 0.0);
    const kdrt::MeshTriangle& mirror_tri = m.mesh.triangles[2];
    CHECK(mirror_tri.material == 1);
    REQUIRE(mirror_tri.n[0] != kdrt::kNoNormal);
    CHECK(near(m.mesh.normals[mirror_tri.n[0]], {0, 0, 1}));
    CHECK(m.mesh.triangles[4].material == 2);
    CHECK(m.mesh.triangles[15].material == 2);
}

TEST_CASE("import: glTF node transforms, camera, lights and metallic-roughness materials", "[import]") {
    const kdrt::ImportedModel m = kdrt::import_model(kModels / "scene.gltf");
    CHECK(m.stats.triangles == 2 + 12 + 12);
    CHECK(m.stats.meshes == 3);
    // The glass cube: a unit cube scaled by 1.5 and moved to (-1, 1.2, 0).
    const kdrt::MeshTriangle& glass_tri = m.mesh.triangles[2];
    for (auto v : glass_tri.v) {
        const glm::dvec3 p = m.mesh.positions[v];
        CHECK(std::abs(std::abs(p.x + 1.0) - 0.75) < 1e-6);
        CHECK(std::abs(std::abs(p.y - 1.2) - 0.75) < 1e-6);
        CHECK(std::abs(std::abs(p.z) - 0.75) < 1e-6);
    }
    CHECK(near(m.bounds.lo, {-5, 0, -5}));
    CHECK(near(m.bounds.hi, {5, 1.95, 5}));

    REQUIRE(m.materials.size() == 3);
    const kdrt::Material& grass = m.materials[0];
    CHECK(grass.name == "scene.gltf:grass");
    CHECK(near(grass.color, {0.2, 0.6, 0.3}));
    CHECK(grass.diffuse == 1.0);
    CHECK(grass.reflect == 0.0);
    CHECK(grass.shininess == Approx(30));   // alpha = 0.5^2: 2 / alpha^2 - 2
    CHECK(grass.specular == Approx(0.25));  // 0.5 (1 - metallic)(1 - roughness)
    const kdrt::Material& glass = m.materials[1];
    CHECK(glass.transmit == Approx(1.0));
    CHECK(glass.ior == Approx(1.33));
    CHECK(glass.diffuse == Approx(0.0));
    const kdrt::Material& chrome = m.materials[2];
    CHECK(chrome.reflect == Approx(0.9));  // metallic (1 - roughness)
    CHECK(chrome.diffuse == Approx(0.1));
    CHECK(chrome.transmit == 0.0);

    REQUIRE(m.cameras.size() == 1);
    const kdrt::ModelCamera& eye = m.cameras[0];
    CHECK(eye.name == "eye");
    CHECK_FALSE(eye.orthographic);
    CHECK(near(eye.camera.position, {0, 2, 8}, 1e-5));
    CHECK(eye.camera.fov_y == Approx(0.8 * 180 / kPi));
    CHECK(eye.aspect == Approx(1.5));
    // Tilted down by 10 degrees about x.
    const glm::dvec3 forward = glm::normalize(eye.camera.look_at - eye.camera.position);
    CHECK(near(forward, {0, -std::sin(10 * kPi / 180), -std::cos(10 * kPi / 180)}, 1e-5));

    REQUIRE(m.lights.size() == 2);
    // Colours times intensity, scaled so that the brightest channel is 1.
    CHECK(near(m.lights[0].position, {3, 6, 4}, 1e-5));
    CHECK(near(m.lights[0].color, {1.0, 0.9, 0.8}, 1e-6));
    // The directional sun points down: a far point light above the centre.
    const glm::dvec3 centre = (m.bounds.lo + m.bounds.hi) * 0.5;
    CHECK(m.lights[1].position.y - centre.y > 100 * (m.bounds.hi.y - m.bounds.lo.y));
    CHECK(std::abs(m.lights[1].position.x - centre.x) < 1e-3);
    CHECK(near(m.lights[1].color, {0.25, 0.25, 0.25}, 1e-6));

    SECTION("a transform moves the triangles, the camera and the lights") {
        const std::array<double, 16> t{2, 0, 0, 10, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1};
        const kdrt::ImportedModel moved = kdrt::import_model(kModels / "scene.gltf", t);
        CHECK(near(moved.bounds.lo, {0, 0, -10}));
        CHECK(near(moved.bounds.hi, {20, 3.9, 10}));
        CHECK(near(moved.cameras[0].camera.position, {10, 4, 16}, 1e-5));
        CHECK(near(moved.lights[0].position, {16, 12, 8}, 1e-5));
    }
    SECTION("scene_from_model uses the file's camera, its aspect and its lights") {
        kdrt::ImportStats stats;
        const kdrt::Scene s = kdrt::scene_from_model(kModels / "scene.gltf", {}, &stats);
        CHECK(stats.triangles == 26);
        CHECK(s.name == "scene");
        CHECK(near(s.camera.position, {0, 2, 8}, 1e-5));
        CHECK(s.settings.height == 500);
        CHECK(s.settings.width == 750);
        CHECK(s.lights.size() == 2);
        CHECK(s.triangle_count() == 26);
        CHECK(s.materials.size() == 3);
    }
}

TEST_CASE("import: every listed format reads a model Assimp wrote", "[import]") {
    TempDir dir;
    const auto grid = grid_scene(6);  // 72 triangles
    aiVector3D lo(1e9f, 1e9f, 1e9f), hi(-1e9f, -1e9f, -1e9f);
    for (unsigned i = 0; i < grid->mMeshes[0]->mNumVertices; ++i) {
        const aiVector3D& v = grid->mMeshes[0]->mVertices[i];
        lo = aiVector3D(std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z));
        hi = aiVector3D(std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z));
    }
    const double grid_volume = double(hi.x - lo.x) * double(hi.y - lo.y) * double(hi.z - lo.z);
    struct Written {
        std::string format, file;
    };
    for (const Written& w : {Written{"ply", "grid-ascii.ply"}, Written{"plyb", "grid-binary.ply"},
                             Written{"stlb", "grid.stl"}, Written{"fbxa", "grid.fbx"}, Written{"obj", "grid.obj"},
                             Written{"gltf2", "grid.gltf"}, Written{"glb2", "grid.glb"}}) {
        INFO(w.file);
        const fs::path p = dir.path / w.file;
        export_scene(*grid, w.format, p);
        REQUIRE(kdrt::is_model_file(p));
        const kdrt::ImportedModel m = kdrt::import_model(p);
        CHECK(m.stats.triangles == 72);
        // Some formats add a unit scale or an axis change: compare the extent's volume.
        const glm::dvec3 e = m.bounds.extent();
        CHECK(std::abs(e.x * e.y * e.z) == Approx(grid_volume).epsilon(1e-4));
        REQUIRE(m.materials.size() == 1);
        // No exponent, no highlight: Assimp's default material for PLY and STL has a white Ks.
        if (p.extension() == ".ply" || p.extension() == ".stl") CHECK(m.materials[0].specular == 0.0);
    }
    SECTION("OFF and a PLY with a bare comment line in its header, written by hand") {
        const fs::path off = dir.write("quad.off", "OFF\n# a quad\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
        CHECK(kdrt::import_model(off).stats.triangles == 2);
        // Old Blender versions wrote such a line; Assimp skips it, and so does the header check.
        const fs::path ply = dir.write("blender.ply", "ply\nformat ascii 1.0\nCreated by Blender3D 247\nelement vertex 3\n"
                                                      "property float x\nproperty float y\nproperty float z\n"
                                                      "element face 1\nproperty list uchar int vertex_indices\n"
                                                      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        CHECK(kdrt::import_model(ply).stats.triangles == 1);
    }
    SECTION("the glTF scene as binary glTF keeps triangles, materials, camera and lights") {
        const fs::path glb = dir.write("scene.glb", pack_glb(read_bytes(kModels / "scene.gltf"), read_bytes(kModels / "scene.bin")));
        const kdrt::ImportedModel a = kdrt::import_model(kModels / "scene.gltf");
        const kdrt::ImportedModel b = kdrt::import_model(glb);
        REQUIRE(b.cameras.size() == 1);
        CHECK(near(b.cameras[0].camera.position, a.cameras[0].camera.position));
        CHECK(near(b.cameras[0].camera.look_at, a.cameras[0].camera.look_at));
        REQUIRE(b.lights.size() == 2);
        CHECK(near(b.lights[1].position, a.lights[1].position));
        CHECK(b.stats.triangles == a.stats.triangles);
        CHECK(near(b.bounds.lo, a.bounds.lo));
        CHECK(near(b.bounds.hi, a.bounds.hi));
        REQUIRE(b.materials.size() == a.materials.size());
        for (std::size_t i = 0; i < a.materials.size(); ++i) {
            CHECK(b.materials[i].transmit == Approx(a.materials[i].transmit));
            CHECK(b.materials[i].reflect == Approx(a.materials[i].reflect));
        }
    }
    CHECK_FALSE(kdrt::is_model_file("scene.json"));
    CHECK_FALSE(kdrt::is_model_file("model.dae"));
    CHECK(kdrt::is_model_file("MODEL.GLB"));
}

TEST_CASE("import: without camera and lights the defaults frame the model", "[import]") {
    TempDir dir;
    const fs::path p = dir.path / "grid.ply";
    export_scene(*grid_scene(8), "plyb", p);
    const kdrt::ImportedModel m = kdrt::import_model(p);
    const kdrt::Scene s = kdrt::scene_from_model(p);
    CHECK(s.settings.width == 500);
    CHECK(s.settings.height == 500);
    CHECK(s.settings.max_depth == 15);
    const glm::dvec3 centre = (m.bounds.lo + m.bounds.hi) * 0.5;
    CHECK(near(s.camera.look_at, centre));
    CHECK(s.camera.position.z > centre.z);  // from the +z side
    CHECK(near(s.camera.up, {0, 1, 0}));
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p3{corner & 1 ? m.bounds.hi.x : m.bounds.lo.x, corner & 2 ? m.bounds.hi.y : m.bounds.lo.y,
                            corner & 4 ? m.bounds.hi.z : m.bounds.lo.z};
        CHECK(in_frame(s.camera, 1.0, p3));
    }
    REQUIRE(s.lights.size() == 1);
    CHECK(s.lights[0].position.y > s.camera.position.y);
    CHECK(near(s.lights[0].color, {1, 1, 1}));

    // The picture: the model in the middle, background at the corners.
    kdrt::RenderOptions o;
    o.device = "cpu";
    o.frame.width = o.frame.height = 32;
    o.frame.want_ids = true;
    const kdrt::RenderResult r = kdrt::render(s, o);
    CHECK(r.ids[16 * 32 + 16] >= 0);
    for (int at : {0, 31, 31 * 32, 32 * 32 - 1}) CHECK(r.ids[static_cast<std::size_t>(at)] == -1);
}

TEST_CASE("import: --camera picks one of the file's cameras", "[import]") {
    CHECK_NOTHROW(kdrt::scene_from_model(kModels / "scene.gltf", {0}));
    for (int bad : {1, -1}) {
        try {
            kdrt::scene_from_model(kModels / "scene.gltf", {bad});
            FAIL("camera " << bad << " accepted");
        } catch (const kdrt::Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK_THAT(e.what(), Contains("scene.gltf") && Contains("camera " + std::to_string(bad)) &&
                                     Contains("1 (0..0)"));
        }
    }
    try {
        kdrt::scene_from_model(kModels / "room.obj", {0});
        FAIL("camera 0 of a file without cameras accepted");
    } catch (const kdrt::Error& e) {
        CHECK_THAT(e.what(), Contains("room.obj") && Contains("no cameras"));
    }
}

TEST_CASE("import: a scene mixes models with its own spheres and triangles", "[import]") {
    kdrt::Scene s;
    const kdrt::MaterialId red = s.add_material({.name = "red", .color = {1, 0, 0}});
    s.add_sphere({0, 5, 0}, 1.0, red);
    s.add_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, red);
    const std::uint32_t room = kdrt::add_model(s, kdrt::import_model(kModels / "room.obj"));
    CHECK(room == 2);  // after the sphere and the loose triangle
    const std::array<double, 16> up{1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1, 0, 0, 0, 0, 1};
    const std::uint32_t gltf = kdrt::add_model(s, kdrt::import_model(kModels / "scene.gltf", up), red);
    CHECK(gltf == 2 + 16);
    CHECK(s.materials.size() == 1 + 3);  // the override adds none
    for (const kdrt::MeshTriangle& t : s.meshes[1].triangles) CHECK(t.material == red);
    CHECK(s.materials[s.meshes[0].triangles[0].material].name == "room.obj:matte");
    // The same model twice: its materials get unique names.
    kdrt::add_model(s, kdrt::import_model(kModels / "room.obj"));
    CHECK(s.materials.back().name == "room.obj:glass#2");
    CHECK(s.materials[s.meshes[2].triangles.back().material].name == "room.obj:glass#2");
    CHECK_NOTHROW(kdrt::validate(s));
    CHECK(s.object_count() == 2 + 16 + 26 + 16);
}

TEST_CASE("import: the material rule on Assimp materials", "[import]") {
    SECTION("glTF alphaMode BLEND lets light through unbent") {
        aiMaterial m;
        const int pbr = aiShadingMode_PBR_BRDF;
        m.AddProperty(&pbr, 1, AI_MATKEY_SHADING_MODEL);
        const float opacity = 0.25f, zero = 0.0f, one = 1.0f;
        m.AddProperty(&opacity, 1, AI_MATKEY_OPACITY);
        m.AddProperty(&zero, 1, AI_MATKEY_METALLIC_FACTOR);
        m.AddProperty(&one, 1, AI_MATKEY_ROUGHNESS_FACTOR);
        const aiString blend("BLEND");
        m.AddProperty(&blend, AI_MATKEY_GLTF_ALPHAMODE);
        const kdrt::Material w = kdrt::detail::whitted_material(m);
        CHECK(w.transmit == Approx(0.75));
        CHECK(w.ior == 1.0);
        CHECK(w.shininess == 1.0);  // roughness 1: the widest lobe allowed
        CHECK(w.specular == 0.0);
    }
    SECTION("out-of-range MTL numbers are clamped into FORMAT.md's ranges") {
        aiMaterial m;
        const int illum = 3;
        m.AddProperty(&illum, 1, AI_MATKEY_OBJ_ILLUM);
        const aiColor3D ks(5, 5, 5), kd(-1, 0.5f, 2);
        m.AddProperty(&ks, 1, AI_MATKEY_COLOR_SPECULAR);
        m.AddProperty(&kd, 1, AI_MATKEY_COLOR_DIFFUSE);
        const float ns = 0.0f, d = 1.5f, ni = -2.0f, nan = std::nanf("");
        m.AddProperty(&ns, 1, AI_MATKEY_SHININESS);
        m.AddProperty(&d, 1, AI_MATKEY_OPACITY);
        m.AddProperty(&ni, 1, AI_MATKEY_REFRACTI);
        m.AddProperty(&nan, 1, AI_MATKEY_SHININESS_STRENGTH);
        const kdrt::Material w = kdrt::detail::whitted_material(m);
        CHECK(w.reflect == 1.0);
        CHECK(w.transmit == 0.0);
        CHECK(w.shininess == 1.0);
        CHECK(w.ior == 1.0);
        CHECK(near(w.color, {0, 0.5, 2}));
        kdrt::Scene s;
        s.add_material(w);
        CHECK_NOTHROW(kdrt::validate(s));
    }
}

TEST_CASE("import: points and lines are skipped and counted, never rendered", "[import]") {
    TempDir dir;
    const fs::path mixed = dir.write("mixed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\nl 1 4\np 4\n");
    const kdrt::ImportedModel m = kdrt::import_model(mixed);
    CHECK(m.stats.triangles == 1);
    CHECK(m.stats.skipped_lines == 1);
    CHECK(m.stats.skipped_points == 1);
    const fs::path only = dir.write("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
    const kdrt::Error e = import_error(only);
    CHECK_THAT(e.what(), Contains("lines.obj") && Contains("no triangles") && Contains("2 lines"));
}

TEST_CASE("import: a missing material library is a warning", "[import]") {
    TempDir dir;
    const fs::path p = dir.write("lonely.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
    const kdrt::ImportedModel m = kdrt::import_model(p);
    CHECK(m.stats.triangles == 1);
    REQUIRE_FALSE(m.stats.warnings.empty());
    CHECK_THAT(m.stats.warnings[0], Contains("lonely.obj") && Contains("gone.mtl"));
    CHECK(m.stats.warnings.size() == 1);
}

TEST_CASE("import: malformed models are errors naming the file", "[import]") {
    TempDir dir;
    const std::string gltf_text = read_bytes(kModels / "scene.gltf");
    const std::string bin = read_bytes(kModels / "scene.bin");
    const auto gltf_with = [&](const std::string& from, const std::string& to) {
        std::string s = gltf_text;
        const std::size_t at = s.find(from);
        REQUIRE(at != std::string::npos);
        return s.replace(at, from.size(), to);
    };
    // A valid .glb to cut short.
    ReadBack gltf(kModels / "scene.gltf");
    const fs::path glb = dir.path / "whole.glb";
    export_scene(*gltf.scene, "glb2", glb);
    const std::string glb_bytes = read_bytes(glb);

    // scene.bin with the ground's first index far out of range (uint16 at offset 144).
    std::string bad_index_bin = bin;
    bad_index_bin[144] = '\xff';
    bad_index_bin[145] = '\x7f';
    fs::create_directories(dir.path / "badindex");
    dir.write("badindex/scene.bin", bad_index_bin);
    dir.write("badindex/scene.gltf", gltf_text);
    dir.write("scene.bin", bin);
    dir.write("short-buffer.bin", bin.substr(0, 100));
    ::mkfifo((dir.path / "fifo.bin").c_str(), 0600);
    ::mkfifo((dir.path / "fifo.obj").c_str(), 0600);
    fs::create_directories(dir.path / "folder.obj");

    std::vector<std::pair<fs::path, std::string>> cases = {
        {dir.write("truncated.glb", glb_bytes.substr(0, glb_bytes.size() / 2)), "truncated .glb"},
        {dir.write("no-bin.gltf", gltf_with("\"uri\": \"scene.bin\"", "\"uri\": \"absent.bin\"")), ".gltf whose .bin is missing"},
        {dir.path / "badindex" / "scene.gltf", "index value out of range"},
        {dir.write("count.gltf", gltf_with("\"count\": 36", "\"count\": 100000")), "index accessor beyond its buffer"},
        {dir.write("short.gltf", gltf_with("\"uri\": \"scene.bin\"", "\"uri\": \"short-buffer.bin\"")), "buffer shorter than declared"},
        {dir.write("fifo.gltf", gltf_with("\"uri\": \"scene.bin\"", "\"uri\": \"fifo.bin\"")), "buffer is a FIFO"},
        {dir.write("zero.gltf", gltf_with("\"uri\": \"scene.bin\"", "\"uri\": \"/dev/zero\"")), "buffer is /dev/zero"},
        {dir.write("type.gltf", gltf_with("\"type\": \"VEC3\"", "\"type\": \"MAT4\"")), "accessor of the wrong type"},
        {dir.write("json.gltf", gltf_text.substr(0, gltf_text.size() / 3)), "truncated JSON"},
        {dir.write("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                              "nan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "NaN in a PLY"},
        {dir.write("inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"), "infinite OBJ vertex"},
        {dir.write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "NaN OBJ vertex"},
        {dir.write("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "OBJ index out of range"},
        {dir.write("huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n\x01\x02"), "PLY declaring 1e9 vertices"},
        // Assimp 5.2 alone loops forever on the first and aborts on the second.
        {dir.write("cut-header.ply", "ply\nformat ascii "), "PLY header cut short"},
        {dir.write("glued.ply", "ply\nformat ascii 1.0\nelement vertex 1\npropend_header\n0 0 0\n"), "PLY end_header glued to a line"},
        {dir.write("empty-face.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                     "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                     "end_header\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n0\n"), "PLY face without indices"},
        {dir.write("keyword.ply", "ply\nformat ascii 1.0\nelement vertex 3\noperty float x\nend_header\n0\n1\n2\n"),
         "PLY vertices without properties"},
        {dir.write("format.ply", "ply\nformat binary_little_endianl1.0\nelement vertex 0\nend_header\n"), "PLY format misspelt"},
        {dir.write("count.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nend_header\n"), "PLY count too large"},
        // Assimp 5.2 alone allocates and loops for minutes on this one (its test corpus's OutOfMemory.off).
        {dir.write("huge.off", "OFF\n353535235358 6 0\n0 0 0\n1 0 0\n0 1 0\n"), "OFF count beyond 2^32"},
        {dir.write("many.off", "OFF\n3000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "OFF counts beyond the file"},
        {dir.write("garbage.ply", with_nuls("\x13\x37garbage\0\xff bytes")), "garbage .ply"},
        {dir.write("garbage.glb", with_nuls("glTF\x02\0\0\0\xff\xff\xff\x7f garbage")), "garbage .glb"},
        {dir.write("garbage.obj", "this is not an OBJ file\n"), "text with an .obj extension"},
        {dir.write("empty.gltf", ""), "empty file"},
        {dir.path / "folder.obj", "a directory"},
        {dir.path / "fifo.obj", "a FIFO"},
        {dir.path / "missing.glb", "no such file"},
        {dir.write("model.xyz", "solid x\nendsolid x\n"), "unsupported extension"},
    };
    for (const auto& [path, what] : cases) {
        INFO(what << ": " << path);
        const kdrt::Error e = import_error(path);
        CHECK_THAT(e.what(), Contains(path.filename().string()));
        CHECK((e.code() == ErrorCode::InvalidScene || e.code() == ErrorCode::Io || e.code() == ErrorCode::Unsupported));
    }
}

// The same picture on both devices for every kind of file: the id maps agree
// but for silhouette pixels and ties (FORMAT.md, as for scene files), and the
// image differs by float noise only.
TEST_CASE("import: the C++ reference and OpenCL render imported models alike", "[import][opencl]") {
    if (!have_opencl()) return;
    TempDir dir;
    ReadBack gltf(kModels / "scene.gltf");
    export_scene(*gltf.scene, "glb2", dir.path / "scene.glb");
    export_scene(*grid_scene(10), "plyb", dir.path / "grid.ply");
    for (const fs::path& p : {kModels / "room.obj", kModels / "scene.gltf", dir.path / "scene.glb", dir.path / "grid.ply"}) {
        INFO(p);
        const kdrt::Scene scene = kdrt::scene_from_model(p);
        kdrt::RenderOptions o;
        o.frame.width = 72;
        o.frame.height = 48;
        o.frame.want_ids = true;
        o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
        o.device = "cpu";
        const kdrt::RenderResult ref = kdrt::render(scene, o);
        o.device = "opencl";
        const kdrt::RenderResult got = kdrt::render(scene, o);
        std::size_t hits = 0;
        for (std::int32_t id : ref.ids) hits += id >= 0;
        CHECK(hits > ref.ids.size() / 50);  // not an empty picture
        const kdrt::IdMapComparison c = kdrt::compare_id_maps(ref, got);
        INFO(c.summary());
        CHECK(c.unexplained == 0);
        CHECK(c.mismatches <= ref.ids.size() / 100);
        CHECK(kdrt::image_rmse(ref.image, got.image) < 4e-3);
    }
}
