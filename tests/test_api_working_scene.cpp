// kdrt/working_scene.h: the seam through which kdrt-bench shades Embree's
// hits with kdrt's own shader.
#include "api_test_scenes.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/kd_tree.h>
#include <kdrt/working_scene.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <memory>

using namespace kdrt;

namespace {

// A scene with every effect: a glass sphere, a mirror, lights.
Scene shading_scene() {
    Scene s = kdrt_test::api_scene(7);
    Material glass;
    glass.transmit = 0.8;
    glass.ior = 1.5;
    const auto g = s.add_material(glass);
    s.add_sphere({1000.0, -250.0, 38.0}, 1.2, g);
    s.add_light({{1000.0 - 6.0, -250.0 + 5.0, 30.0}, {0.6, 0.6, 0.6}});
    return s;
}

}  // namespace

TEST_CASE("api: WorkingScene shades its own traversal's hits into the cpu device's image, pixel for pixel", "[api]") {
    const Scene scene = shading_scene();
    RenderOptions o;
    o.commit.accel = Accel::KdTree;
    o.commit.traversal = Traversal::Stack;
    const WorkingScene ws(scene, o);
    REQUIRE(ws.features().refraction);
    REQUIRE(ws.features().reflection);
    auto tree = std::make_shared<const KdTree>(build_kd_tree(ws.build_input(), o.commit.tree));
    o.commit.tree_files.in_memory = tree;
    const RenderResult expected = CommittedScene::commit(Device::open("cpu"), scene, o.commit).render(o.frame);

    const std::unique_ptr<ShadingIntersector> kd = ws.kd_intersector(*tree, Traversal::Stack);
    RayCounts counts;
    int differ = 0;
    for (int y = 0; y < ws.height(); ++y)
        for (int x = 0; x < ws.width(); ++x) {
            const ShadingRay ray = ws.camera_ray(x, y);
            ++counts.camera;
            const glm::vec3 c = ws.shade(ray, kd->closest(ray), *kd, counts);
            const glm::vec3 e = expected.image.at(x, y);
            differ += c != e;
        }
    CHECK(differ == 0);
    CHECK(counts.camera == expected.stats.rays.camera);
    CHECK(counts.shadow == expected.stats.rays.shadow);
    CHECK(counts.secondary == expected.stats.rays.secondary);
    CHECK(counts.secondary > 0);
}

TEST_CASE("api: WorkingScene's geometry is the scene's, moved into the working frame, ids mapped", "[api]") {
    Scene scene;
    scene.camera.position = {500.0, 0.0, -10.0};
    scene.camera.look_at = {500.0, 0.0, 0.0};
    const auto m = scene.add_material({});
    const auto tri = scene.add_triangle({499.0, 0.0, 0.0}, {501.0, 0.0, 0.0}, {500.0, 1.0, 0.0}, m);  // id 0
    const auto sph = scene.add_sphere({500.0, -2.0, 1.0}, 0.5, m);                                   // id 1
    const WorkingScene ws(scene);
    REQUIRE(ws.sphere_count() == 1);
    REQUIRE(ws.triangle_count() == 1);
    // Object indices put spheres first; object_id gives back what add_* returned.
    CHECK(ws.object_id(0) == sph);
    CHECK(ws.object_id(1) == tri);
    const glm::dvec3 o = ws.frame_origin();
    CHECK(glm::length(glm::dvec3(ws.sphere(0).center) + o - glm::dvec3(500.0, -2.0, 1.0)) < 1e-4);
    CHECK(ws.sphere(0).radius == Approx(0.5));
    CHECK(glm::length(glm::dvec3(ws.triangle(0).v1) + o - glm::dvec3(501.0, 0.0, 0.0)) < 1e-4);
    // The camera ray through the image centre heads along the view direction, from the camera.
    const ShadingRay r = ws.camera_ray(ws.width() / 2, ws.height() / 2);
    CHECK(glm::length(glm::dvec3(r.origin) + o - scene.camera.position) < 1e-4);
    CHECK(r.direction.z > 0.99f);
    CHECK(r.leaving == -1);
    CHECK_THROWS_AS(ws.sphere(1), std::out_of_range);
}
