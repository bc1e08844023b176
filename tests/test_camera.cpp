// Camera rays follow FORMAT.md's formula.
#include <kdrt/camera.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <cmath>

TEST_CASE("camera: centre and corner pixels follow FORMAT.md", "[camera]") {
    kdrt::Camera cam;
    cam.position = {0, 0, 0};
    cam.look_at = {0, 0, 1};
    cam.up = {0, 1, 0};
    cam.fov_y = 90.0;  // t = tan(45 deg) = 1
    const int W = 5, H = 3;
    kdrt::CameraFrame f(cam, W, H);
    // forward = +z, right = cross(forward, up) = (-1, 0, 0), up2 = (0, 1, 0).
    CHECK(f.right.x == Approx(-1.0));
    CHECK(f.up.y == Approx(1.0));

    // Centre pixel (2, 1) of a 5x3 image: u = v = 0, straight ahead.
    glm::dvec3 d = f.direction(2, 1, W, H);
    CHECK(d.x == Approx(0.0).margin(1e-15));
    CHECK(d.y == Approx(0.0).margin(1e-15));
    CHECK(d.z == Approx(1.0));

    // Top-left pixel (0, 0): u = (2*0.5/5 - 1) * 1 * 5/3 = -4/3, v = (1 - 2*0.5/3) = 2/3.
    const double u = -4.0 / 3.0, v = 2.0 / 3.0;
    glm::dvec3 expect = glm::normalize(glm::dvec3(0, 0, 1) + u * glm::dvec3(-1, 0, 0) + v * glm::dvec3(0, 1, 0));
    d = f.direction(0, 0, W, H);
    CHECK(d.x == Approx(expect.x));
    CHECK(d.y == Approx(expect.y));
    CHECK(d.z == Approx(expect.z));

    // Bottom-right pixel (4, 2): the mirror image.
    d = f.direction(4, 2, W, H);
    CHECK(d.x == Approx(-expect.x));
    CHECK(d.y == Approx(-expect.y));
}

TEST_CASE("camera: a tilted camera keeps an orthonormal frame", "[camera]") {
    kdrt::Camera cam;
    cam.position = {4, 5.5, -5};
    cam.look_at = {0, 0, 0};
    cam.up = {0, 1, 0};
    cam.fov_y = 40;
    kdrt::CameraFrame f(cam, 500, 500);
    CHECK(glm::dot(f.forward, f.right) == Approx(0.0).margin(1e-12));
    CHECK(glm::dot(f.forward, f.up) == Approx(0.0).margin(1e-12));
    CHECK(glm::length(f.up) == Approx(1.0));
    CHECK(f.tan_half_fov == Approx(std::tan(20.0 * 3.14159265358979 / 180.0)));
    glm::dvec3 c = f.direction(250, 250, 500, 500, 0.0, 0.0);  // the image centre is a pixel corner
    CHECK(glm::dot(c, f.forward) == Approx(1.0));
}

TEST_CASE("camera: sample offsets stay inside the pixel and are deterministic", "[camera]") {
    for (int n : {1, 4, 5, 9, 16, 7}) {
        for (int s = 0; s < n; ++s) {
            double x, y, x2, y2;
            kdrt::sample_offset(s, n, x, y);
            kdrt::sample_offset(s, n, x2, y2);
            CHECK(x == x2);
            CHECK(y == y2);
            CHECK(x > 0.0);
            CHECK(x < 1.0);
            CHECK(y > 0.0);
            CHECK(y < 1.0);
        }
    }
    double x, y;
    kdrt::sample_offset(0, 1, x, y);
    CHECK(x == 0.5);
    CHECK(y == 0.5);
}
