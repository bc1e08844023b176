// kdrt::intersect / kdrt::occluded on the cpu device: every traversal, both
// precisions, against brute force over every object (the intersection
// functions, no tree), on random and adversarial rays and t windows.
#include "api_test_scenes.h"
#include "walks.h"

#include "cpu/intersect.h"
#include "scene/prepared_scene.h"

#include <kdrt/error.h>
#include <kdrt/ray_query.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <thread>
#include <vector>

using namespace kdrt;

namespace {

QueryRay query(glm::dvec3 o, glm::dvec3 d, float t_min = 0.0f, float t_max = std::numeric_limits<float>::infinity()) {
    return {{float(o.x), float(o.y), float(o.z)}, t_min, {float(d.x), float(d.y), float(d.z)}, t_max};
}

// The closest hit by testing every object: the oracle. Same working-frame
// ray as the library's (origin - frame origin in double, unit direction),
// both sphere roots, ties to the lower id. Returns internal id and query t.
template <class Real>
std::pair<std::int32_t, double> brute_force(const detail::PreparedScene& p, const QueryRay& q, bool moller) {
    using Vec = glm::vec<3, Real>;
    const glm::dvec3 o(q.origin[0], q.origin[1], q.origin[2]), d(q.direction[0], q.direction[1], q.direction[2]);
    const double len = glm::length(d);
    const detail::Ray<Real> ray(Vec(o - p.frame_origin), Vec(d / len));
    const auto& g = p.geometry<Real>();
    std::int32_t best = -1;
    double best_t = std::numeric_limits<double>::infinity();
    Real best_unit = std::numeric_limits<Real>::infinity();
    auto consider = [&](std::int32_t id, Real t_unit) {
        const double t = double(t_unit) / len;
        if (!(t_unit > 0) || !(t > q.t_min) || !(t <= q.t_max)) return false;
        if (t_unit < best_unit || (t_unit == best_unit && id < best)) {
            best = id;
            best_unit = t_unit;
            best_t = t;
        }
        return true;
    };
    for (std::size_t i = 0; i < g.spheres.size(); ++i) {
        Real t0, t1;
        if (!detail::sphere_roots(ray, g.spheres[i].center, g.spheres[i].radius, t0, t1)) continue;
        if (!consider(std::int32_t(i), t0)) consider(std::int32_t(i), t1);
    }
    for (std::size_t i = 0; i < g.triangles.size(); ++i) {
        const auto& t = g.triangles[i];
        Real th, b1, b2;
        const bool hit = moller ? detail::intersect_triangle_moller(ray, t.v0, t.v1, t.v2, th, b1, b2)
                                : detail::intersect_triangle(ray, t.v0, t.v1, t.v2, th, b1, b2);
        if (hit) consider(std::int32_t(g.spheres.size() + i), th);
    }
    return {best, best_t};
}

// Random rays with non-unit directions, and the adversarial ones: along the
// tree's split planes, through the grid's shared vertices and edges, grazing
// spheres, and windows that end or start exactly at a hit.
std::vector<QueryRay> test_rays(const Scene& scene, const detail::PreparedScene& p, const KdTree* tree,
                                std::uint32_t seed) {
    std::mt19937 rng(seed);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    const glm::dvec3 c = p.frame_origin;
    auto point = [&] { return c + glm::dvec3(rnd(-7, 7), rnd(-7, 7), rnd(-7, 7)); };
    std::vector<QueryRay> rays;
    for (int i = 0; i < 300; ++i) {
        const glm::dvec3 o = point(), target = c + glm::dvec3(rnd(-4, 4), rnd(-4, 4), rnd(-4, 4));
        rays.push_back(query(o, (target - o) * rnd(0.01, 5.0)));
    }
    if (tree)
        for (std::size_t n = 0; n < tree->nodes.size() && rays.size() < 600; ++n) {
            if (kd_is_leaf(tree->nodes[n])) continue;
            const int axis = kd_axis(tree->nodes[n]);
            glm::dvec3 o = point(), d(rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
            o[axis] = c[axis] + double(kd_split(tree->nodes[n]));
            d[axis] = 0.0;  // in the split plane
            if (glm::length(d) > 0) rays.push_back(query(o, d));
        }
    for (const Mesh& m : scene.meshes)
        for (const MeshTriangle& t : m.triangles) {
            const glm::dvec3 o = point(), v = m.positions[t.v[0]], e = 0.5 * (m.positions[t.v[0]] + m.positions[t.v[1]]);
            rays.push_back(query(o, v - o));
            rays.push_back(query(o, e - o));
        }
    for (const Sphere& s : scene.spheres) {
        // Grazing: along a tangent, a hair inside and outside.
        for (double r : {s.radius, s.radius * (1 - 1e-6), s.radius * (1 + 1e-6)})
            rays.push_back(query(s.center + glm::dvec3(0, r, -10), {0, 0, 1}));
    }
    return rays;
}

// Windows ending and starting exactly at each ray's closest hit.
void add_windows(std::vector<QueryRay>& rays, const std::vector<QueryHit>& hits) {
    const std::size_t n = rays.size();
    for (std::size_t i = 0; i < n; ++i) {
        if (hits[i].object == KDRT_NO_HIT) continue;
        QueryRay up_to = rays[i], after = rays[i], before = rays[i];
        up_to.t_max = hits[i].t;
        after.t_min = hits[i].t;
        before.t_max = std::nextafter(hits[i].t, 0.0f);
        rays.insert(rays.end(), {up_to, after, before});
    }
}

}  // namespace

TEST_CASE("api: ray queries equal brute force on every structure, traversal and precision", "[api]") {
    const Scene scene = kdrt_test::api_scene(7);
    const Device cpu = Device::open("cpu");
    for (Precision precision : {Precision::Float, Precision::Double})
        for (const kdrt_test::Walk walk : kdrt_test::kAllWalks)
            for (TriangleTest test : {TriangleTest::Watertight, TriangleTest::MollerTrumbore}) {
                CAPTURE(to_string(precision), walk, to_string(test));
                CommitOptions o;
                o.accuracy.precision = precision;
                walk.apply(o);
                o.accuracy.triangle_test = test;
                o.tree.max_depth = 12;  // many split planes for the adversarial rays
                const CommittedScene committed = CommittedScene::commit(cpu, scene, o);
                const detail::PreparedScene p = detail::prepare_scene(scene, o);
                std::vector<QueryRay> rays = test_rays(scene, p, committed.tree(), 11);
                std::vector<QueryHit> hits(rays.size());
                intersect(committed, rays, hits);
                add_windows(rays, hits);
                hits.resize(rays.size());
                intersect(committed, rays, hits);
                std::vector<std::uint8_t> blocked(rays.size());
                occluded(committed, rays, blocked);
                const bool moller = test == TriangleTest::MollerTrumbore;
                std::size_t hit_count = 0;
                for (std::size_t i = 0; i < rays.size(); ++i) {
                    const auto [id, t] = precision == Precision::Double ? brute_force<double>(p, rays[i], moller)
                                                                        : brute_force<float>(p, rays[i], moller);
                    CAPTURE(i);
                    if (id < 0) {
                        CHECK(hits[i].object == KDRT_NO_HIT);
                        CHECK(blocked[i] == 0);
                        continue;
                    }
                    ++hit_count;
                    REQUIRE(hits[i].object == std::uint32_t(id));
                    CHECK(hits[i].t == float(t));
                    CHECK(blocked[i] == 1);
                    const bool sphere = std::size_t(id) < p.geometry_f.spheres.size();
                    CHECK(hits[i].kind == (sphere ? KDRT_KIND_SPHERE : KDRT_KIND_TRIANGLE));
                    const glm::dvec3 n(hits[i].normal[0], hits[i].normal[1], hits[i].normal[2]);
                    CHECK(glm::length(n) == Approx(1.0).epsilon(1e-5));
                    if (!sphere) {
                        CHECK(hits[i].u >= -1e-6f);
                        CHECK(hits[i].v >= -1e-6f);
                        CHECK(hits[i].u + hits[i].v <= 1.0f + 1e-5f);
                    }
                }
                CHECK(hit_count > rays.size() / 4);  // the rays do find things
            }
}

TEST_CASE("api: t is in units of the given direction and the window excludes t_min and includes t_max", "[api]") {
    Scene s;
    auto m = s.add_material({});
    s.add_sphere({100, 0, 0}, 1.0, m);
    s.add_triangle({90, -1, -1}, {90, 1, -1}, {90, 0, 2}, m);  // behind the origin: never hit for t > 0
    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), s, {});
    // Direction of length 2 from x = 95: the sphere spans t in [2, 3].
    std::vector<QueryRay> rays{query({95, 0, 0}, {2, 0, 0}), query({95, 0, 0}, {2, 0, 0}, 0.0f, 2.0f),
                               query({95, 0, 0}, {2, 0, 0}, 2.0f), query({95, 0, 0}, {2, 0, 0}, 0.0f, 1.999f),
                               query({95, 0, 0}, {2, 0, 0}, 3.0f)};
    std::vector<QueryHit> hits(rays.size());
    intersect(c, rays, hits);
    CHECK(hits[0].t == Approx(2.0f));
    CHECK(hits[0].object == 0u);
    CHECK(hits[0].normal[0] == Approx(-1.0f));
    CHECK(hits[1].t == Approx(2.0f));  // t_max is inclusive
    CHECK(hits[2].t == Approx(3.0f));  // t_min is exclusive: the far side
    CHECK(hits[2].normal[0] == Approx(1.0f));
    CHECK(hits[3].object == KDRT_NO_HIT);
    CHECK(hits[4].object == KDRT_NO_HIT);
    // A negative t_min acts as 0 (docs/API.md): the triangle behind the origin, at t = -2.5, is never hit.
    std::vector<QueryRay> back{query({95, 0, 0}, {2, 0, 0}, -10.0f, 10.0f), query({95, 0, 0}, {-2, 0, 0}, -10.0f, 1.0f)};
    std::vector<QueryHit> back_hits(back.size());
    intersect(c, back, back_hits);
    CHECK(back_hits[0].object == 0u);
    CHECK(back_hits[0].t == Approx(2.0f));
    CHECK(back_hits[1].object == KDRT_NO_HIT);  // the sphere lies at t in [-3, -2] of this ray
    std::vector<std::uint8_t> blocked(back.size(), 7);
    occluded(c, back, blocked);
    CHECK(blocked[0] == 1);
    CHECK(blocked[1] == 0);
}

TEST_CASE("api: invalid rays miss and wrong span sizes are refused", "[api]") {
    const Scene scene = kdrt_test::api_scene(3);
    const CommittedScene c = CommittedScene::commit(Device::open("cpu"), scene, {});
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const glm::dvec3 o = scene.camera.position, d = scene.camera.look_at - o;
    std::vector<QueryRay> rays{query(o, d), query(o, {0, 0, 0}), query(o, d, 5.0f, 1.0f), query(o, d, nan),
                               query(o, d, 0.0f, nan), query({nan, 0, 0}, d), query(o, {inf, 0, 0})};
    std::vector<QueryHit> hits(rays.size());
    intersect(c, rays, hits);
    std::vector<std::uint8_t> blocked(rays.size(), 7);
    occluded(c, rays, blocked);
    CHECK(hits[0].object != KDRT_NO_HIT);  // the valid one hits the scene's middle
    CHECK(blocked[0] == 1);
    for (std::size_t i = 1; i < rays.size(); ++i) {
        CAPTURE(i);
        CHECK(hits[i].object == KDRT_NO_HIT);
        CHECK(blocked[i] == 0);
    }
    hits.resize(2);
    CHECK_THROWS_AS(intersect(c, rays, hits), Error);
}

TEST_CASE("api: several threads query one committed scene at once", "[api][parallel]") {
    const Scene scene = kdrt_test::api_scene(5);
    const detail::PreparedScene p = detail::prepare_scene(scene, {});
    for (const Accel accel : {Accel::Bvh, Accel::KdTree}) {
        CAPTURE(to_string(accel));
        CommitOptions o;
        o.accel = accel;
        const CommittedScene c = CommittedScene::commit(Device::open("cpu"), scene, o);
        const std::vector<QueryRay> rays = test_rays(scene, p, c.tree(), 3);  // with a kd-tree, also through its planes
        std::vector<QueryHit> expected(rays.size());
        intersect(c, rays, expected);
        std::vector<std::vector<QueryHit>> got(4, std::vector<QueryHit>(rays.size()));
        std::vector<std::vector<std::uint8_t>> blocked(4, std::vector<std::uint8_t>(rays.size()));
        std::vector<std::thread> threads;
        for (std::size_t k = 0; k < got.size(); ++k)
            threads.emplace_back([&, k] {
                intersect(c, rays, got[k]);
                occluded(c, rays, blocked[k]);
            });
        for (std::thread& t : threads) t.join();
        for (std::size_t k = 0; k < got.size(); ++k)
            for (std::size_t i = 0; i < rays.size(); ++i) {
                REQUIRE(got[k][i].object == expected[i].object);
                REQUIRE(blocked[k][i] == (expected[i].object != KDRT_NO_HIT ? 1 : 0));
            }
    }
}

TEST_CASE("api: several threads commit, render and query on one device at once", "[api][parallel]") {
    // device.h: a Device may be shared by threads, each with its own
    // CommittedScene. Every thread's frame must equal the one rendered alone.
    const Device device = Device::open("cpu");
    std::vector<Scene> scenes;
    std::vector<Image> alone;
    for (std::uint32_t k = 0; k < 3; ++k) {
        scenes.push_back(kdrt_test::api_scene(10 + k));
        alone.push_back(CommittedScene::commit(device, scenes.back(), {}).render().image);
    }
    std::vector<Image> together(scenes.size());
    std::vector<std::uint32_t> hit_objects(scenes.size(), 0);
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < scenes.size(); ++k)
        threads.emplace_back([&, k] {
            FrameOptions frame;
            frame.threads = 2;
            const CommittedScene c = CommittedScene::commit(device, scenes[k]);
            together[k] = c.render(frame).image;
            const glm::dvec3 o = scenes[k].camera.position, d = scenes[k].camera.look_at - o;
            const QueryRay ray{{float(o.x), float(o.y), float(o.z)}, 0.f, {float(d.x), float(d.y), float(d.z)}, 1e30f};
            QueryHit hit{};
            intersect(c, std::span(&ray, 1), std::span(&hit, 1));
            hit_objects[k] = hit.object;
        });
    for (std::thread& t : threads) t.join();
    for (std::size_t k = 0; k < scenes.size(); ++k) {
        CAPTURE(k);
        REQUIRE(together[k].rgb == alone[k].rgb);
        REQUIRE(hit_objects[k] != KDRT_NO_HIT);  // the camera looks at the grid behind the objects
    }
}

// Consecutive coherent rays go through the packet traversal (4 rays of one
// direction octant share a stack); rays queried one at a time never do. The
// two must agree bit for bit, hits and shadow answers, with per-ray windows,
// invalid rays breaking packets up, and fans that straddle the axis planes.
TEST_CASE("api: coherent rays in packets answer as each ray alone", "[api]") {
    const Scene scene = kdrt_test::api_scene(5);
    const Device cpu = Device::open("cpu");
    std::mt19937 rng(3);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    for (Precision precision : {Precision::Float, Precision::Double})
        for (const kdrt_test::Walk walk : {kdrt_test::Walk{Accel::KdTree, Traversal::Stack},
                                           kdrt_test::Walk{Accel::KdTree, Traversal::ShortStack},
                                           kdrt_test::Walk{Accel::Bvh, Traversal::Stack}}) {
            CAPTURE(to_string(precision), walk);
            CommitOptions o;
            o.accuracy.precision = precision;
            walk.apply(o);
            const CommittedScene committed = CommittedScene::commit(cpu, scene, o);
            const glm::dvec3 eye = scene.camera.position, centre = scene.camera.look_at;
            std::vector<QueryRay> rays;
            for (int y = 0; y < 48; ++y)
                for (int x = 0; x < 64; ++x) {
                    const glm::dvec3 target = centre + glm::dvec3((x - 32) * 0.15, (y - 24) * 0.15, rnd(-0.01, 0.01));
                    QueryRay q = query(eye, (target - eye) * rnd(0.5, 2.0));
                    if (x % 5 == 1) q.t_max = float(rnd(0.5, 40.0));  // windows that cut some lanes short
                    if (x % 7 == 3) q.t_min = float(rnd(0.0, 10.0));
                    if (x == 13) q.direction[0] = std::numeric_limits<float>::quiet_NaN();  // invalid: breaks a packet
                    rays.push_back(q);
                }
            // Rays from inside the scene, parallel, through the tree's planes.
            for (int i = 0; i < 400; ++i) {
                const glm::dvec3 org = centre + glm::dvec3(rnd(-3, 3), rnd(-3, 3), rnd(-3, 3));
                rays.push_back(query(org + glm::dvec3(0, 0.01 * (i % 4), 0), {0.3, -0.5, 0.8}));
            }
            std::size_t same_octant = 0;
            for (std::size_t i = 0; i + 4 <= rays.size(); i += 4) {
                bool same = true;
                for (std::size_t k = 1; k < 4; ++k)
                    for (int a = 0; a < 3; ++a)
                        same &= (rays[i + k].direction[a] > 0) == (rays[i].direction[a] > 0);
                same_octant += same;
            }
            CHECK(same_octant > rays.size() / 8);  // packets do form
            std::vector<QueryHit> hits(rays.size());
            std::vector<std::uint8_t> blocked(rays.size());
            intersect(committed, rays, hits);
            occluded(committed, rays, blocked);
            std::size_t mismatches = 0, hit_count = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                QueryHit alone{};
                std::uint8_t alone_blocked = 2;
                intersect(committed, std::span(&rays[i], 1), std::span(&alone, 1));
                occluded(committed, std::span(&rays[i], 1), std::span(&alone_blocked, 1));
                hit_count += alone.object != KDRT_NO_HIT;
                // Bit for bit: QueryHit is all 4-byte fields, no padding.
                const bool same = std::memcmp(&alone, &hits[i], sizeof(QueryHit)) == 0 && alone_blocked == blocked[i];
                if (!same && mismatches < 5)
                    UNSCOPED_INFO("ray " << i << ": packet " << hits[i].object << "@" << hits[i].t << " blocked "
                                         << int(blocked[i]) << ", alone " << alone.object << "@" << alone.t
                                         << " blocked " << int(alone_blocked));
                mismatches += !same;
            }
            CHECK(hit_count > rays.size() / 4);
            CHECK(mismatches == 0);
        }
}
