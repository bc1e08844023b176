// The C++ reference renderer: pixels computed by hand, scale invariance.
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include "scene_transform.h"

#include <catch2/catch.hpp>

#include <string>

namespace {

// One lit sphere seen head-on; a 3x3 image so the centre pixel's ray is the
// view axis and its colour can be worked out on paper.
kdrt::Scene single_sphere(double reflect = 0.0) {
    kdrt::Scene s;
    s.camera.position = {0, 0, -5};
    s.camera.look_at = {0, 0, 0};
    s.camera.up = {0, 1, 0};
    s.camera.fov_y = 30;
    s.settings.width = s.settings.height = 3;
    s.settings.ambient = {0.1, 0.1, 0.1};
    s.settings.background = {0.0, 0.25, 0.5};
    kdrt::Material m;
    m.color = {1.0, 0.5, 0.25};
    m.diffuse = 0.8;
    m.specular = 0.5;
    m.shininess = 10;
    m.reflect = reflect;
    auto id = s.add_material(m);
    s.add_sphere({0, 0, 0}, 1.0, id);
    s.add_light({{0, 0, -10}, {1, 1, 1}});
    return s;
}

}  // namespace

TEST_CASE("reference: a lit sphere's centre pixel matches the hand computation", "[render]") {
    // Hit (0,0,-1), N = L = R = -D: c = ambient*C*kd + (kd*C*1 + ks*1^n)
    //   = C * (0.1*0.8 + 0.8) + 0.5 = (1.38, 0.94, 0.72).
    for (auto precision : {kdrt::Precision::Float, kdrt::Precision::Double}) {
        kdrt::RenderOptions o;
        o.commit.traversal = kdrt::Traversal::None;
        o.commit.accuracy.precision = precision;
        o.frame.want_ids = true;
        kdrt::RenderResult r = kdrt::render(single_sphere(), o);
        glm::vec3 c = r.image.at(1, 1);
        CHECK(c.x == Approx(1.38f).epsilon(1e-5));
        CHECK(c.y == Approx(0.94f).epsilon(1e-5));
        CHECK(c.z == Approx(0.72f).epsilon(1e-5));
        CHECK(r.ids[4] == 0);
        CHECK(r.hit_t[4] == Approx(4.0f));
        // Corner pixels miss the sphere and show the background.
        glm::vec3 bg = r.image.at(0, 0);
        CHECK(bg.x == 0.0f);
        CHECK(bg.y == 0.25f);
        CHECK(bg.z == 0.5f);
        CHECK(r.ids[0] == -1);
        CHECK(r.stats.rays.camera == 9);
        CHECK(r.stats.rays.shadow == 1 + 4);  // the centre and the 4 edge pixels that see the sphere lit
    }
}

TEST_CASE("reference: a mirror sphere reflects the background back along the axis", "[render]") {
    // With reflect 0.5 the centre ray bounces straight back to the camera side
    // and misses everything: c += 0.5 * background.
    kdrt::RenderOptions o;
    o.commit.traversal = kdrt::Traversal::None;
    kdrt::RenderResult r = kdrt::render(single_sphere(0.5), o);
    glm::vec3 c = r.image.at(1, 1);
    CHECK(c.x == Approx(1.38f + 0.0f).epsilon(1e-5));
    CHECK(c.y == Approx(0.94f + 0.125f).epsilon(1e-5));
    CHECK(c.z == Approx(0.72f + 0.25f).epsilon(1e-5));
    CHECK(r.stats.rays.secondary == 5);
    // max_depth 1: no bounce at all.
    o.frame.max_depth = 1;
    r = kdrt::render(single_sphere(0.5), o);
    CHECK(r.image.at(1, 1).y == Approx(0.94f).epsilon(1e-5));
    CHECK(r.stats.rays.secondary == 0);
}

TEST_CASE("reference: a scene without mirrors or glass traces no secondary rays", "[render][features]") {
    kdrt::RenderOptions o;
    o.commit.traversal = kdrt::Traversal::None;
    kdrt::RenderResult r = kdrt::render(single_sphere(), o);
    CHECK(r.stats.features.max_depth == 1);
    CHECK_FALSE(r.stats.features.reflection);
    CHECK_FALSE(r.stats.features.refraction);
    CHECK(r.stats.rays.secondary == 0);
    kdrt::Scene dark = single_sphere();
    dark.lights.clear();
    r = kdrt::render(dark, o);
    CHECK_FALSE(r.stats.features.lights);
    CHECK(r.stats.rays.shadow == 0);
}

// FORMAT.md: the same scene translated by 1e5 or scaled by 1e-3 gives the same
// picture. The working frame centred on the scene keeps float precision, and
// every epsilon is relative to the objects. Bound: RMSE below 2e-3 (half an
// 8-bit step) and at most 0.5% of the camera hits on another object.
TEST_CASE("reference: lens is the same picture moved by 1e5 and shrunk by 1e-3", "[render][stability]") {
    kdrt::Scene lens = kdrt::load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json");
    kdrt::RenderOptions o;
    o.frame.width = o.frame.height = 160;
    o.commit.traversal = kdrt::Traversal::None;
    o.frame.want_ids = true;
    for (auto precision : {kdrt::Precision::Float, kdrt::Precision::Double}) {
        o.commit.accuracy.precision = precision;
        kdrt::RenderResult base = kdrt::render(lens, o);
        for (auto [scale, offset] : {std::pair{1.0, glm::dvec3(1e5, -1e5, 1e5)}, std::pair{1e-3, glm::dvec3(0.0)},
                                     std::pair{1e-3, glm::dvec3(-3e4, 2e4, 1e5)}}) {
            INFO("precision " << kdrt::to_string(precision) << ", scale " << scale << ", offset " << offset.x);
            kdrt::RenderResult moved = kdrt::render(kdrt::test::transformed(lens, scale, offset), o);
            double rmse = kdrt::image_rmse(base.image, moved.image);
            CHECK(rmse < 2e-3);
            std::size_t differ = 0;
            for (std::size_t i = 0; i < base.ids.size(); ++i) differ += base.ids[i] != moved.ids[i];
            CHECK(differ <= base.ids.size() / 200);
        }
    }
}
