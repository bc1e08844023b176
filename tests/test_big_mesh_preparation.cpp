// A big mesh is checked and copied into the working frame in parallel chunks
// (common/parallel_chunks.h). These tests pin what a serial pass gave: the
// first fault in index order is the one named, shading normals keep their
// order across chunks, and the scene's box and material count come out whole.
#include <catch2/catch.hpp>

#include "scene/prepared_scene.h"

#include <kdrt/error.h>
#include <kdrt/commit_options.h>
#include <kdrt/scene.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <string>

using namespace kdrt;
using Catch::Matchers::Contains;

namespace {

// A strip of `count` triangles (several chunks' worth), every third with
// shading normals of its own; materials 0 and 1, with 2 on one late triangle.
Scene strip_scene(std::uint32_t count) {
    Scene scene;
    scene.add_material(Material{});
    scene.add_material(Material{});
    scene.add_material(Material{});
    scene.camera.position = {0.5 * count, 0.5, -10.0};
    scene.camera.look_at = {0.5 * count, 0.5, 0.0};
    Mesh m;
    for (std::uint32_t i = 0; i <= count; ++i) {
        m.positions.push_back({double(i), 0.0, 0.01 * (i % 7)});
        m.positions.push_back({double(i), 1.0, -0.01 * (i % 5)});
    }
    m.positions.push_back({-1e6, 0.0, 0.0});  // referenced by no triangle
    for (std::uint32_t i = 0; i < count; ++i) {
        MeshTriangle t;
        t.v = {2 * i, 2 * i + 1, 2 * i + 2};
        t.material = i == count - 10 ? 2 : i % 2;
        if (i % 3 == 0) {
            for (std::uint32_t k = 0; k < 3; ++k) {
                t.n[k] = static_cast<std::uint32_t>(m.normals.size());
                m.normals.push_back({0.1 * k, 1.0 + i, 2.0});
            }
        }
        m.triangles.push_back(t);
    }
    scene.add_mesh(std::move(m));
    return scene;
}

std::string error_of(const Scene& scene) {
    try {
        (void)detail::prepare_scene(scene, CommitOptions{});
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidScene);
        return e.what();
    }
    return "no error";
}

}  // namespace

TEST_CASE("a big mesh is prepared as a serial pass would prepare it", "[scene][parallel]") {
    constexpr std::uint32_t kCount = 70000;  // five chunks
    const Scene scene = strip_scene(kCount);
    const detail::PreparedScene p = detail::prepare_scene(scene, CommitOptions{});
    const auto& g = p.geometry_f;
    REQUIRE(g.triangles.size() == kCount);
    REQUIRE(g.normals.size() == 3 * ((kCount + 2) / 3));
    const Mesh& m = scene.meshes[0];
    std::uint32_t next_normal = 0;
    std::size_t wrong = 0;
    for (std::uint32_t i = 0; i < kCount; ++i) {
        const auto& t = g.triangles[i];
        const glm::vec3 v0(m.positions[m.triangles[i].v[0]] - p.frame_origin);
        wrong += t.v0 != v0 || t.material != m.triangles[i].material;
        if (i % 3 == 0) {
            wrong += t.normals != next_normal;
            for (std::uint32_t k = 0; k < 3; ++k, ++next_normal)
                wrong += g.normals[next_normal] != glm::vec3(glm::normalize(m.normals[m.triangles[i].n[k]]));
        } else {
            wrong += t.normals != kNoNormal;
        }
    }
    CHECK(wrong == 0);
    CHECK(p.material_refs == 3);  // the one material-2 triangle sits in the last chunk
    Aabb world;  // the extra last position is used by no triangle, and moves no box
    for (std::size_t i = 0; i + 1 < m.positions.size(); ++i) world.extend(m.positions[i]);
    CHECK(p.frame_origin == 0.5 * (world.lo + world.hi));
    CHECK(p.bounds.lo == world.lo - p.frame_origin);
    CHECK(p.bounds.hi == world.hi - p.frame_origin);
}

TEST_CASE("a big mesh's first fault in index order is the one named", "[scene][validate][parallel]") {
    constexpr std::uint32_t kCount = 70000;
    SECTION("positions") {
        Scene scene = strip_scene(kCount);
        scene.meshes[0].positions[60001].y = NAN;
        scene.meshes[0].positions[40003].z = INFINITY;
        CHECK_THAT(error_of(scene), Contains("meshes[0].positions[40003]"));
    }
    SECTION("normals") {
        Scene scene = strip_scene(kCount);
        scene.meshes[0].normals[50000] = glm::dvec3(0.0);
        scene.meshes[0].normals[33000] = glm::dvec3(0.0);
        CHECK_THAT(error_of(scene), Contains("meshes[0].normals[33000]") && Contains("non-zero length"));
    }
    SECTION("triangles") {
        Scene scene = strip_scene(kCount);
        scene.meshes[0].triangles[65000].material = 9;
        scene.meshes[0].triangles[41000].n[1] = 1u << 30;
        scene.meshes[0].triangles[52000].v[2] = 1u << 30;
        CHECK_THAT(error_of(scene), Contains("meshes[0][41000]") && Contains("normal index"));
        scene.meshes[0].triangles[41000].n[1] = kNoNormal;
        CHECK_THAT(error_of(scene), Contains("meshes[0][52000]") && Contains("vertex index"));
        scene.meshes[0].triangles[52000].v[2] = 0;
        CHECK_THAT(error_of(scene), Contains("meshes[0][65000].material") && Contains("undefined material"));
    }
}
