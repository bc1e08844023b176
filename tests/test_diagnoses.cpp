// Bad input is diagnosed for what it is: a far camera is not a parallel up
// vector, a strong shear is not a singular matrix, an enum value cast from an
// integer is refused before any switch meets it.
#include "scene/affine_transform.h"

#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene.h>

#include <catch2/catch.hpp>

#include <string>

using namespace kdrt;

namespace {

Scene one_sphere() {
    Scene s;
    s.name = "diagnoses";
    s.materials.push_back(Material{});
    s.spheres.push_back(Sphere{});
    s.settings.width = s.settings.height = 4;
    return s;
}

std::string error_of(const Scene& scene) {
    try {
        validate(scene);
    } catch (const Error& e) {
        return e.what();
    }
    return {};
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("a camera far away is out of range, not a parallel up vector", "[diagnoses]") {
    Scene s = one_sphere();
    REQUIRE(error_of(s).empty());
    s.camera.position = {0, 0, -1e300};
    const std::string far = error_of(s);
    CHECK(has(far, "camera.look_at"));
    CHECK(has(far, "float range"));
    CHECK_FALSE(has(far, "parallel"));

    s.camera.position = {0, 0, -1e-200};  // tiny but non-zero distances are fine
    s.camera.look_at = {0, 0, 0};
    CHECK(error_of(s).empty());
    s.camera.up = {0, 1e200, 0};  // so is a huge up vector
    CHECK(error_of(s).empty());
    s.camera.up = {0, 0, 5};
    CHECK(has(error_of(s), "parallel"));
    s.camera.up = {0, 0, 0};
    CHECK(has(error_of(s), "must not be zero"));
}

TEST_CASE("a shear with determinant 1 is not called singular", "[diagnoses]") {
    using detail::affine_transform_problem;
    CHECK(affine_transform_problem({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}).empty());
    CHECK(affine_transform_problem({1, 1e6, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}).empty());
    const std::string strong = affine_transform_problem({1, 1e13, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
    CHECK_FALSE(has(strong, "singular"));
    CHECK(has(strong, "ill-conditioned"));
    CHECK(has(strong, "determinant 1"));
    CHECK(has(affine_transform_problem({1, 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 0, 1}), "singular matrix (determinant 0)"));
}

TEST_CASE("option enums out of range are refused with the field's name", "[diagnoses]") {
    const Scene s = one_sphere();
    auto error_for = [&](auto set) {
        RenderOptions o;
        o.device = "cpu";
        set(o);
        try {
            render(s, o);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            return std::string(e.what());
        }
        return std::string();
    };
    CHECK(error_for([](RenderOptions&) {}).empty());
    CHECK(has(error_for([](RenderOptions& o) { o.commit.accel = static_cast<Accel>(5); }), "CommitOptions::accel is 5"));
    CHECK(has(error_for([](RenderOptions& o) { o.commit.traversal = static_cast<Traversal>(99); }), "CommitOptions::traversal is 99"));
    CHECK(has(error_for([](RenderOptions& o) { o.commit.accuracy.precision = static_cast<Precision>(-1); }), "CommitOptions::accuracy.precision"));
    CHECK(has(error_for([](RenderOptions& o) { o.frame.opencl.ray_order = static_cast<RayOrder>(3); }), "FrameOptions::opencl.ray_order"));
    CHECK(has(error_for([](RenderOptions& o) { o.commit.tree.builder = static_cast<KdBuilderKind>(7); }), "tree.builder"));
    CHECK(has(error_for([](RenderOptions& o) { o.frame.samples = 5000; }), "samples is 5000, at most 4096"));
}
