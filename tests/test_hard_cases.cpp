// Hard cases that must stay numerically stable, on the C++ reference and on
// every OpenCL device (PoCL in CI), for every traversal of both structures and both precisions.
// Each scene is built in code; each bound is stated where it is checked.
#include "have_opencl.h"
#include "opencl/cl_devices.h"

#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include "scene_transform.h"
#include "walks.h"

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

// The devices every hard case runs on: the C++ reference and each OpenCL device.
std::vector<std::string> devices() {
    std::vector<std::string> d{"cpu"};
    const auto cl = detail::ocl::enumerate_devices();
    for (const auto& dev : cl) d.push_back(dev.info.id);
    if (cl.empty()) WARN("no OpenCL device: hard cases run on the C++ reference only");
    return d;
}

bool device_has_fp64(const std::string& device) {
    if (device == "cpu") return true;
    return detail::ocl::select_device(device).info.fp64;
}

using kdrt_test::Walk;

RenderOptions options_for(const std::string& device, Walk w, Precision p) {
    RenderOptions o;
    o.device = device;
    w.apply(o.commit);
    o.commit.accuracy.precision = p;
    o.frame.want_ids = true;
    o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    return o;
}

// Runs `check` for every device, walk and precision.
template <class Check>
void everywhere(Check&& check) {
    for (const std::string& device : devices())
        for (const Walk w : kdrt_test::kAllWalks)
            for (Precision p : {Precision::Float, Precision::Double}) {
                if (p == Precision::Double && !device_has_fp64(device)) continue;
                INFO("device " << device << ", " << w << ", precision " << to_string(p));
                check(options_for(device, w, p));
            }
}

// A geodesic sphere: an icosahedron subdivided `levels` times (20 * 4^levels
// triangles), vertices shared between neighbouring triangles, facing inwards
// and outwards alike (both faces are hit).
Mesh icosphere(glm::dvec3 centre, double radius, int levels, MaterialId material) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<std::uint32_t, 3>> f = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
        {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (auto& p : v) p = glm::normalize(p);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto middle = [&](std::uint32_t a, std::uint32_t b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back(glm::normalize(v[a] + v[b]));
            return mid[key] = static_cast<std::uint32_t>(v.size() - 1);
        };
        std::vector<std::array<std::uint32_t, 3>> next;
        for (auto& tri : f) {
            std::uint32_t a = middle(tri[0], tri[1]), b = middle(tri[1], tri[2]), c = middle(tri[2], tri[0]);
            next.push_back({tri[0], a, c});
            next.push_back({tri[1], b, a});
            next.push_back({tri[2], c, b});
            next.push_back({a, b, c});
        }
        f = std::move(next);
    }
    Mesh m;
    for (auto& p : v) m.positions.push_back(centre + radius * p);
    for (auto& tri : f) {
        MeshTriangle mt;
        mt.v = tri;
        mt.material = material;
        m.triangles.push_back(mt);
    }
    return m;
}

// A background that appears nowhere else: red 1000 while every surface has no
// red at all (no red in colours, no specular, no red light or ambient). A ray
// escaping at any depth adds weight * 1000 to a pixel's red channel.
constexpr double kLeakRed = 1000.0;

Material no_red(glm::dvec3 color, double reflect, double transmit = 0.0) {
    Material m;
    m.color = {0.0, color.y, color.z};
    m.diffuse = 0.7;
    m.specular = 0.0;
    m.reflect = reflect;
    m.transmit = transmit;
    return m;
}

}  // namespace

// No pixel may show the background: red stays exactly 0 at every depth, and
// every camera ray hits (a leak is a crack between triangles or a ray escaping
// through a surface).
TEST_CASE("hard: camera inside a closed tessellated sphere sees no background", "[hard][leak][slow]") {
    for (int levels : {4, 6}) {  // 5120 and 81920 triangles
        Scene s;
        s.camera.position = {0.31, -0.17, 0.23};
        s.camera.look_at = {2.0, 0.6, 1.1};
        s.camera.fov_y = 100;
        s.settings.background = {kLeakRed, 0.0, 0.0};
        s.settings.ambient = {0.0, 0.2, 0.2};
        s.settings.max_depth = 6;
        const MaterialId wall = s.add_material(no_red({0, 0.6, 0.8}, 0.6));
        const MaterialId glass = s.add_material(no_red({0, 1, 1}, 0.1, 0.9));
        s.add_mesh(icosphere({0.013, -0.021, 0.007}, 3.0, levels, wall));
        s.add_sphere({1.1, 0.3, 0.6}, 0.5, glass);
        s.add_light({{-0.5, 1.2, -0.4}, {0.0, 1.0, 1.0}});
        INFO(s.triangle_count() << " triangles");
        everywhere([&](RenderOptions o) {
            // Brute force over 81920 triangles is too slow for a test: it gets the coarser sphere.
            if (o.commit.traversal == Traversal::None && levels > 4) return;
            o.frame.width = o.frame.height = levels > 4 ? 40 : 24;
            const RenderResult r = render(s, o);
            std::size_t leaks = 0, misses = 0;
            for (std::size_t i = 0; i < r.ids.size(); ++i) {
                misses += r.ids[i] < 0;
                leaks += r.image.rgb[3 * i] != 0.0f;
            }
            CHECK(misses == 0);
            CHECK(leaks == 0);
        });
    }
}

// A grid of unit quads, two triangles each, whose lines lie on the kd-tree's
// split planes, seen head-on with pixel centres aimed at the grid lines and
// vertices: a crack would show the background.
TEST_CASE("hard: rays aimed at shared edges and vertices of a grid never slip through", "[hard][leak]") {
    Scene s;
    const int W = 48;
    const double spacing = 0.125;  // grid lines every 2 pixels
    const double half = W / 2 * spacing / 2;  // the plane z = 0 seen from z = -3 spans [-half, half]
    s.camera.position = {spacing / 4, spacing / 4, -3.0};  // pixel centres land on multiples of spacing/2
    s.camera.look_at = {spacing / 4, spacing / 4, 0.0};
    s.camera.fov_y = 2.0 * std::atan(half / 3.0) * 180.0 / 3.14159265358979323846;
    s.settings.width = s.settings.height = W;
    s.settings.background = {kLeakRed, 0, 0};
    s.settings.ambient = {0, 0.3, 0.3};
    const MaterialId m = s.add_material(no_red({0, 0.5, 0.9}, 0.0));
    Mesh grid;
    const int n = 32;  // the grid reaches beyond the view: only cracks can show the background
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) grid.positions.push_back({(x - n / 2) * spacing, (y - n / 2) * spacing, 0.0});
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const std::uint32_t a = static_cast<std::uint32_t>(y * (n + 1) + x), b = a + 1,
                                c = a + static_cast<std::uint32_t>(n + 1), d = c + 1;
            MeshTriangle t1, t2;
            t1.v = {a, b, d};
            t2.v = {a, d, c};
            t1.material = t2.material = m;
            grid.triangles.push_back(t1);
            grid.triangles.push_back(t2);
        }
    s.add_mesh(grid);
    // A fan of 9 triangles around a shared vertex in front of the grid.
    Mesh fan;
    fan.positions.push_back({spacing / 4, spacing / 4, -0.5});
    for (int i = 0; i < 9; ++i) {
        const double a = 2 * 3.14159265358979323846 * i / 9;
        fan.positions.push_back({spacing / 4 + 0.4 * std::cos(a), spacing / 4 + 0.4 * std::sin(a), -0.5 + 0.05 * (i % 2)});
    }
    for (std::uint32_t i = 0; i < 9; ++i) {
        MeshTriangle t;
        t.v = {0, 1 + i, 1 + (i + 1) % 9};
        t.material = m;
        fan.triangles.push_back(t);
    }
    s.add_mesh(fan);
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        std::size_t leaks = 0;
        for (std::size_t i = 0; i < r.ids.size(); ++i) leaks += r.ids[i] < 0 || r.image.rgb[3 * i] != 0.0f;
        CHECK(leaks == 0);
    });
}

// Bound: RMSE below 2e-3 (half an 8-bit step) and at most 1% of the camera
// ids different (silhouette pixels), against the scene at its own place.
TEST_CASE("hard: the same picture at its place, moved 1e5 away and shrunk by 1e-3", "[hard][scale][slow]") {
    const Scene base = load_scene(std::string(KDRT_SCENES_DIR) + "/insane.json");
    everywhere([&](RenderOptions o) {
        o.frame.width = o.frame.height = 48;
        o.frame.max_depth = 6;
        const RenderResult ref = render(base, o);
        for (auto [scale, offset] : {std::pair{1.0, glm::dvec3(1e5, -1e5, 1e5)}, std::pair{1e-3, glm::dvec3(0.0)}}) {
            INFO("scale " << scale << ", offset " << offset.x);
            const RenderResult r = render(kdrt::test::transformed(base, scale, offset), o);
            CHECK(image_rmse(ref.image, r.image) < 2e-3);
            std::size_t differ = 0;
            for (std::size_t i = 0; i < ref.ids.size(); ++i) differ += ref.ids[i] != r.ids[i];
            CHECK(differ <= ref.ids.size() / 100);
        }
    });
}

// Grazing rays along a large plane (the camera 0.02 above a floor 200 wide),
// axis-parallel rays lying in split planes (the middle row of pixels runs
// exactly in the plane y = 0.02 of the boxes' tops, where the SAH builder
// splits; ray direction y is exactly +0), and rays starting exactly on a
// surface (mirror and shadow rays from the floor and from spheres resting on
// it): every device, traversal and precision gives the picture of brute force
// in double, within RMSE 1e-2 (float against double at grazing angles).
TEST_CASE("hard: grazing and in-plane rays agree with brute force", "[hard]") {
    Scene s;
    s.camera.position = {0.0, 0.02, -6.0};
    s.camera.look_at = {0.0, 0.02, 0.0};
    s.camera.fov_y = 40;
    s.settings.width = s.settings.height = 41;  // odd: the middle row has v = 0
    s.settings.background = {0.1, 0.1, 0.3};
    s.settings.ambient = {0.1, 0.1, 0.1};
    s.settings.max_depth = 4;
    const MaterialId floor = s.add_material({.name = "floor", .color = {0.8, 0.8, 0.8}, .reflect = 0.5});
    const MaterialId ball = s.add_material({.name = "ball", .color = {0.9, 0.3, 0.2}, .specular = 0.5});
    s.add_triangle({-100, 0, -100}, {100, 0, 100}, {100, 0, -100}, floor);
    s.add_triangle({-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, floor);
    for (int i = -2; i <= 2; ++i) s.add_sphere({i * 1.0, 0.5, 2.0}, 0.5, ball);  // resting on the floor
    // Flat boxes 0.02 high: their tops lie in the plane of the camera's middle row.
    for (int i = -3; i <= 3; ++i) {
        const double x = i * 0.7, z = 0.5 + 0.3 * (i & 1);
        s.add_triangle({x, 0.02, z}, {x + 0.5, 0.02, z}, {x + 0.5, 0.02, z + 0.5}, ball);
        s.add_triangle({x, 0.02, z}, {x + 0.5, 0.02, z + 0.5}, {x, 0.02, z + 0.5}, ball);
        s.add_triangle({x, 0.0, z}, {x + 0.5, 0.0, z}, {x + 0.5, 0.02, z}, ball);
        s.add_triangle({x, 0.0, z}, {x + 0.5, 0.02, z}, {x, 0.02, z}, ball);
    }
    s.add_light({{0, 5, -5}, {1, 1, 1}});
    const RenderResult ref = render(s, options_for("cpu", {Accel::KdTree, Traversal::None}, Precision::Double));
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        CHECK(image_rmse(ref.image, r.image) < 1e-2);
        for (float c : r.image.rgb) REQUIRE(std::isfinite(c));
    });
}

// Radius 1e-4 and 1e4 in one scene, seen from inside the huge sphere: the
// tiny one must appear where it should and the huge one must surround the
// camera with no pixel of background.
TEST_CASE("hard: tiny and huge spheres, and a camera inside a sphere", "[hard]") {
    Scene s;
    s.camera.position = {0, 0, -1e-3};
    s.camera.look_at = {0, 0, 0};
    s.camera.fov_y = 20;
    s.settings.width = s.settings.height = 33;
    s.settings.background = {kLeakRed, 0, 0};
    s.settings.ambient = {0, 0.2, 0.2};
    s.settings.max_depth = 3;
    const MaterialId a = s.add_material(no_red({0, 0.5, 0.5}, 0.3));
    const MaterialId b = s.add_material(no_red({0, 0.9, 0.1}, 0.0));
    const std::uint32_t huge = s.add_sphere({0, 0, 0}, 1e4, a);
    const std::uint32_t tiny = s.add_sphere({0, 0, 0}, 1e-4, b);
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        const std::size_t centre = 16 * 33 + 16, corner = 0;
        CHECK(r.ids[centre] == static_cast<std::int32_t>(tiny));
        CHECK(r.hit_t[centre] == Approx(1e-3 - 1e-4).epsilon(1e-3));
        CHECK(r.ids[corner] == static_cast<std::int32_t>(huge));
        std::size_t leaks = 0;
        for (std::size_t i = 0; i < r.ids.size(); ++i) leaks += r.ids[i] < 0 || r.image.rgb[3 * i] != 0.0f;
        CHECK(leaks == 0);
    });
}

// Total internal reflection: a camera inside a glass sphere (ior 1.5) at
// 0.9 R from the centre, looking along a chord, meets the wall at sin = 0.9 >
// 1/1.5. Every bounce meets it at the same angle, so all energy stays in the
// mirror ray: with ambient only, the pixel is exactly max_depth times the
// local term. Energy lost to a refracted ray would make it darker.
TEST_CASE("hard: total internal reflection keeps the energy in the mirror ray", "[hard]") {
    Scene s;
    s.camera.position = {0, 0.9, 0};
    s.camera.look_at = {1, 0.9, 0};
    s.camera.fov_y = 1;
    s.settings.width = s.settings.height = 1;
    s.settings.background = {1, 1, 1};
    s.settings.ambient = {0.5, 0.5, 0.5};
    s.settings.max_depth = 7;
    Material glass;
    glass.color = {0.4, 0.2, 0.1};
    glass.diffuse = 0.1;
    glass.transmit = 1.0;
    glass.ior = 1.5;
    s.add_sphere({0, 0, 0}, 1.0, s.add_material(glass));
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        const glm::vec3 c = r.image.at(0, 0);
        // 7 bounces x ambient 0.5 x kd 0.1 x colour.
        CHECK(c.x == Approx(7 * 0.5 * 0.1 * 0.4).epsilon(1e-4));
        CHECK(c.y == Approx(7 * 0.5 * 0.1 * 0.2).epsilon(1e-4));
        CHECK(c.z == Approx(7 * 0.5 * 0.1 * 0.1).epsilon(1e-4));
        CHECK(r.stats.rays.secondary == 6);
    });
}

// FORMAT.md step 2: vertex normals that disagree with the winding (here all
// three point away from the camera and the light, as in models exported with
// the other handedness) are turned to the geometric normal's side. Head-on,
// with the light at the camera, the pixel is then exactly light x kd x colour;
// left as they were, dot(Ns, L) < 0 and the triangle renders black.
TEST_CASE("hard: shading normals that disagree with the winding are flipped to it", "[hard][slow]") {
    Scene s;
    s.camera.position = {0, 0, -5};
    s.camera.look_at = {0, 0, 0};
    s.camera.fov_y = 1;
    s.settings.width = s.settings.height = 1;
    s.settings.max_depth = 1;
    Material m;
    m.color = {0.8, 0.4, 0.2};
    m.diffuse = 0.5;
    const MaterialId id = s.add_material(m);
    s.add_light({{0, 0, -5}, {1, 1, 1}});
    for (const bool front_facing : {true, false}) {
        Mesh mesh;
        mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
        if (!front_facing) std::swap(mesh.positions[1], mesh.positions[2]);
        // Ng = cross(v1 - v0, v2 - v0) is +z for the first winding, -z for the other;
        // the normals point along Ng's opposite in both cases.
        const double away = front_facing ? -1.0 : 1.0;
        mesh.normals = {{0, 0, away}, {0, 0.1, away}, {0.1, 0, away}};
        MeshTriangle t;
        t.v = {0, 1, 2};
        t.n = {0, 1, 2};
        t.material = id;
        mesh.triangles = {t};
        Scene scene = s;
        scene.add_mesh(mesh);
        INFO("winding " << (front_facing ? "+z" : "-z"));
        everywhere([&](RenderOptions o) {
            const glm::vec3 c = render(scene, o).image.at(0, 0);
            // Ns is at most 0.14 rad off the light direction: cos >= 0.99.
            CHECK(c.x == Approx(0.5 * 0.8).epsilon(0.01));
            CHECK(c.y == Approx(0.5 * 0.4).epsilon(0.01));
            CHECK(c.z == Approx(0.5 * 0.2).epsilon(0.01));
        });
    }
}

// Refraction through a glass slab, worked out with Snell's law: a ray at 30
// degrees enters a slab 1 thick (ior 1.5), runs at asin(sin 30 / 1.5) = 19.47
// degrees inside, leaves parallel to where it came from, and meets a small
// target 1 further on, 0.93 across instead of the 1.15 it would reach
// unbent. With ambient light only, the pixel is exactly the target's local
// colour (the glass adds nothing: kd = 0, no reflection).
TEST_CASE("hard: refraction through a slab follows Snell's law", "[hard]") {
    Scene s;
    const double deg = 3.14159265358979323846 / 180.0;
    s.camera.position = {0, 0, -1};
    s.camera.look_at = {std::sin(30 * deg), 0, -1 + std::cos(30 * deg)};
    s.camera.fov_y = 0.01;
    s.settings.width = s.settings.height = 1;
    s.settings.background = {0, 0, 0};
    s.settings.ambient = {1, 1, 1};
    s.settings.max_depth = 4;
    Material glass;
    glass.diffuse = 0.0;
    glass.transmit = 1.0;
    glass.ior = 1.5;
    const MaterialId g = s.add_material(glass);
    Material target;
    target.color = {0.2, 0.6, 0.4};
    target.diffuse = 0.5;
    const MaterialId t = s.add_material(target);
    // The slab: front face z = 0 facing -z, back face z = 1 facing +z (the
    // winding tells inside from outside, FORMAT.md step 2), wide enough.
    s.add_triangle({-5, -5, 0}, {5, 5, 0}, {5, -5, 0}, g);
    s.add_triangle({-5, -5, 0}, {-5, 5, 0}, {5, 5, 0}, g);
    s.add_triangle({-5, -5, 1}, {5, -5, 1}, {5, 5, 1}, g);
    s.add_triangle({-5, -5, 1}, {5, 5, 1}, {-5, 5, 1}, g);
    const double inside = std::asin(std::sin(30 * deg) / 1.5);
    const double x = std::tan(30 * deg) + std::tan(inside) + std::tan(30 * deg);  // at z = 2
    s.add_triangle({x - 0.02, -0.02, 2}, {x + 0.02, -0.02, 2}, {x + 0.02, 0.02, 2}, t);
    s.add_triangle({x - 0.02, -0.02, 2}, {x + 0.02, 0.02, 2}, {x - 0.02, 0.02, 2}, t);
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        const glm::vec3 c = r.image.at(0, 0);
        CHECK(c.x == Approx(0.1).epsilon(1e-4));
        CHECK(c.y == Approx(0.3).epsilon(1e-4));
        CHECK(c.z == Approx(0.2).epsilon(1e-4));
        CHECK(r.stats.rays.secondary == 2);
    });
}

// Zero-area, collinear and repeated-vertex triangles stay in the scene (FORMAT.md)
// but are never hit; NaN and infinite values are rejected before any device sees them.
TEST_CASE("hard: degenerate triangles are never hit, NaN and inf are rejected", "[hard][validate]") {
    Scene s;
    s.camera.position = {0, 0, -3};
    s.camera.look_at = {0, 0, 0};
    s.settings.width = s.settings.height = 24;
    const MaterialId m = s.add_material({});
    s.add_triangle({-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, m);
    const auto zero = s.add_triangle({0, 0, -1}, {0, 0, -1}, {0, 0, -1}, m);
    const auto collinear = s.add_triangle({-2, 0, -1}, {0, 0, -1}, {2, 0, -1}, m);
    const auto repeated = s.add_triangle({-1, -1, -1}, {1, 1, -1}, {-1, -1, -1}, m);
    everywhere([&](RenderOptions o) {
        const RenderResult r = render(s, o);
        for (std::int32_t id : r.ids) {
            CHECK(id != static_cast<std::int32_t>(zero));
            CHECK(id != static_cast<std::int32_t>(collinear));
            CHECK(id != static_cast<std::int32_t>(repeated));
        }
    });
    const auto rejected = [](const Scene& bad_scene, const char* place) {
        try {
            render(bad_scene, RenderOptions{});
            FAIL("accepted a non-finite " << place);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidScene);
            CHECK(std::string(e.what()).find(place) != std::string::npos);
        }
    };
    for (double bad : {std::nan(""), double(INFINITY), -double(INFINITY)}) {
        Scene t = s;
        t.triangles.positions[1].y = bad;
        rejected(t, "triangles.positions[1]");
        Scene u = s;
        u.add_sphere({0, 0, 0}, bad, m);
        rejected(u, "spheres[0].radius");
        Scene v = s;
        v.camera.position.x = bad;
        rejected(v, "camera.position");
        Scene w = s;
        w.add_light({{0, bad, 0}, {1, 1, 1}});
        rejected(w, "lights[0].position");
    }
    // Finite but beyond what float geometry can hold.
    Scene far = s;
    far.add_sphere({1e39, 0, 0}, 1.0, m);
    CHECK_THROWS_AS(render(far, RenderOptions{}), Error);
}

// Huge objects close to the camera: a ground triangle of half-size 1e9 and
// 1e15 under a camera 1 unit above it, and a camera inside a sphere of radius
// 1e18 and 1e20 (spheres keep the 1e30 range in float; triangles beyond 1e18
// are refused in float). Every scene is inside the accepted range; the ground
// must be hit where a small ground is hit, at the same distance, and the
// sphere on every pixel at about its radius.
TEST_CASE("hard: huge ground triangle and huge enclosing sphere near the camera", "[hard][scale][slow]") {
    auto ground = [](double half) {
        Scene s;
        s.camera.position = {0.1, 1.0, 0.2};
        s.camera.look_at = {0.1, 0.0, 5.2};
        s.camera.fov_y = 60;
        s.settings.width = 64;
        s.settings.height = 32;
        s.settings.max_depth = 2;
        const MaterialId m = s.add_material(no_red({0, 0.6, 0.4}, 0.0));
        s.add_triangle({-half, 0, -half}, {half, 0, -half}, {0, 0, half}, m);
        s.add_sphere({0.1, 0.5, 3.0}, 0.5, s.add_material(no_red({0, 0.2, 0.9}, 0.0)));  // casts a shadow
        s.add_light({{0.1, 4.0, 3.0}, {0, 1, 1}});
        return s;
    };
    const Scene small = ground(10.0);
    for (double half : {1e9, 1e15}) {
        INFO("ground half-size " << half);
        const Scene big = ground(half);
        everywhere([&](RenderOptions o) {
            const RenderResult want = render(small, o);
            const RenderResult got = render(big, o);
            // Same ids, distances and colours (lit where lit, in the sphere's
            // shadow where shadowed) wherever the small ground is seen.
            std::size_t hits = 0, bottom = 0, far_off = 0, shaded_off = 0;
            for (std::size_t i = 0; i < want.ids.size(); ++i) {
                if (want.ids[i] < 0) continue;  // the small ground's horizon is nearer
                ++bottom;
                hits += got.ids[i] == want.ids[i];
                far_off += got.ids[i] == want.ids[i] && std::abs(got.hit_t[i] - want.hit_t[i]) > 1e-4 * want.hit_t[i];
                for (int c = 0; c < 3; ++c)
                    shaded_off += std::abs(got.image.rgb[3 * i + c] - want.image.rgb[3 * i + c]) > 1e-3f;
            }
            CHECK(bottom >= 64 * 12);
            CHECK(hits == bottom);
            CHECK(far_off == 0);
            CHECK(shaded_off == 0);
        });
    }
    // Beyond 1e18 float products of triangle coordinates overflow: float
    // refuses the scene and says so, double renders it.
    {
        const Scene beyond = ground(1e19);
        try {
            render(beyond, RenderOptions{});
            FAIL("a float ground of half-size 1e19 was accepted");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidScene);
            CHECK(std::string(e.what()).find("triangles reaches 1e+19") != std::string::npos);
            CHECK(std::string(e.what()).find("--precision double") != std::string::npos);
        }
        everywhere([&](RenderOptions o) {
            if (o.commit.accuracy.precision == Precision::Float) return;
            const RenderResult want = render(small, o);
            const RenderResult got = render(beyond, o);
            for (std::size_t i = 0; i < want.ids.size(); ++i)
                if (want.ids[i] >= 0) CHECK(got.ids[i] == want.ids[i]);
        });
    }
    for (double radius : {1e18, 1e20}) {
        INFO("sphere radius " << radius);
        Scene s;
        s.camera.position = {0.3, -0.2, 0.1};
        s.camera.look_at = {1.0, 0.4, 2.0};
        s.camera.fov_y = 90;
        s.settings.width = s.settings.height = 24;
        s.settings.background = {kLeakRed, 0, 0};
        s.settings.ambient = {0, 0.2, 0.2};
        s.settings.max_depth = 3;
        const MaterialId m = s.add_material(no_red({0, 0.5, 0.5}, 0.3));
        const std::uint32_t id = s.add_sphere({0, 0, 0}, radius, m);
        s.add_light({{0.0, 0.5, 0.0}, {0, 1, 1}});
        everywhere([&](RenderOptions o) {
            const RenderResult r = render(s, o);
            std::size_t misses = 0, leaks = 0;
            for (std::size_t i = 0; i < r.ids.size(); ++i) {
                misses += r.ids[i] != static_cast<std::int32_t>(id) || !(std::abs(r.hit_t[i] - radius) < 1e-3 * radius);
                leaks += r.image.rgb[3 * i] != 0.0f;
            }
            CHECK(misses == 0);
            CHECK(leaks == 0);
        });
    }
}
