// count_hits, all_hits and closest_points on OpenCL (cl/every_hit.cl,
// cl/closest_point.cl) against the cpu device on the same prepared scene and
// the same structure: kd-trees that reference objects from several leaves
// (their repeats dropped on the host), the wide BVH and no structure; on a
// CPU device as it is and described as a GPU (the kernels a GPU gets, staged
// host memory), in float and double, and on a device without fp64. Rays:
// random ones with windows, along and through the shared edges and vertices
// of a grid, from inside a closed mesh, through spheres, invalid ones; points:
// near and far, on the surface, at sphere centres, non-finite. Skips with a
// warning without OpenCL.
#include "api_test_scenes.h"
#include "have_opencl.h"
#include "kdtree/tree_provider.h"
#include "opencl/cl_devices.h"
#include "opencl/opencl_backend.h"
#include "render/device_state.h"
#include "scene/prepared_scene.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/ray_query.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

using kdrt_test::have_opencl;

const glm::dvec3 kOffset{300.0, -120.0, 45.0};
constexpr float kInf = std::numeric_limits<float>::infinity();

// api_scene's spheres, triangles and grid of quads (z = 2, shared edges and
// vertices), with a closed box around the origin (|x|, |y| <= 1.5, |z| <= 1)
// and a big sphere that rays cross twice.
Scene hit_scene() {
    Scene s = kdrt_test::api_scene(9, kOffset);
    Mesh box;
    for (int i = 0; i < 8; ++i)
        box.positions.push_back(kOffset + glm::dvec3(i & 1 ? 1.5 : -1.5, i & 2 ? 1.5 : -1.5, i & 4 ? 1.0 : -1.0));
    const std::uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& f : faces) box.triangles.push_back({{f[0], f[1], f[2]}, {kNoNormal, kNoNormal, kNoNormal}, 0});
    s.add_mesh(std::move(box));
    s.add_sphere(kOffset + glm::dvec3(0, 0, -3), 1.25, 0);
    return s;
}

// A commit of the scene on an OpenCL backend and on the cpu device, on one
// prepared scene and structure: internal ids on both sides.
struct Pair {
    PreparedScene prepared;
    std::shared_ptr<const KdTree> tree;
    std::shared_ptr<const WideBvh> bvh;
    BackendWork work;
    std::unique_ptr<SceneBackend> cl, cpu;
    AccelRef accel() const { return {tree.get(), bvh.get()}; }
};

CommitOptions options(Traversal traversal, Accel accel, Precision precision) {
    CommitOptions o;
    o.traversal = traversal;
    o.accel = accel;
    o.accuracy.precision = precision;
    o.tree.traversal_cost = 0.05;  // a deep kd-tree: objects in several leaves
    o.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    return o;
}

std::unique_ptr<Pair> commit_pair(DeviceBackend& cl, const Scene& scene, const CommitOptions& o) {
    auto p = std::make_unique<Pair>();
    p->prepared = prepare_scene(scene, o);
    if (o.traversal != Traversal::None) {
        if (o.accel == Accel::Bvh) p->bvh = provide_bvh(p->prepared, o).bvh;
        else p->tree = provide_tree(p->prepared, o).tree;
    }
    if (p->tree) REQUIRE(p->tree->leaf_objects.size() > p->tree->object_count);
    p->cl = cl.commit(p->prepared, p->accel(), o, p->work);
    static const Device cpu = Device::open("cpu");
    p->cpu = DeviceAccess::backend(cpu, "test").commit(p->prepared, p->accel(), o, p->work);
    return p;
}

DeviceBackend& opencl_device() {
    static const std::unique_ptr<DeviceBackend> device = make_opencl_backend(ocl::select_device("opencl"));
    return *device;
}

// The OpenCL device described as a GPU with memory of its own (as in
// test_opencl_queries.cpp): the GPU kernels, staged host memory.
DeviceBackend& described_as_gpu() {
    static const std::unique_ptr<DeviceBackend> device = [] {
        ocl::ClDevice d = ocl::select_device("opencl");
        d.info.type = "gpu";
        d.host_memory = false;
        return make_opencl_backend(d);
    }();
    return *device;
}

DeviceBackend& without_fp64() {
    static const std::unique_ptr<DeviceBackend> device = [] {
        ocl::ClDevice d = ocl::select_device("opencl");
        d.info.fp64 = false;
        return make_opencl_backend(d);
    }();
    return *device;
}

QueryRay ray(const glm::dvec3& o, const glm::dvec3& d, float t_min = 0.0f, float t_max = kInf) {
    QueryRay r{};
    for (int a = 0; a < 3; ++a) {
        r.origin[a] = static_cast<float>(kOffset[a] + o[a]);
        r.direction[a] = static_cast<float>(d[a]);
    }
    r.t_min = t_min;
    r.t_max = t_max;
    return r;
}

// Random rays with windows that cut their hit lists, unnormalised directions.
void add_random_rays(std::vector<QueryRay>& rays, std::uint32_t seed, int n) {
    std::mt19937 rng(seed);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 o(rnd(-8, 8), rnd(-8, 8), rnd(-8, 8)), t(rnd(-4, 4), rnd(-4, 4), rnd(-4, 4));
        const float t_min = i % 5 == 0 ? float(rnd(0, 0.5)) : i % 11 == 0 ? -1.0f : 0.0f;
        const float t_max = i % 7 == 0 ? float(rnd(0.3, 1.0)) : kInf;
        rays.push_back(ray(o, (t - o) * rnd(0.2, 3.0), t_min, t_max));
    }
}

// The hard cases: the grid's shared edges and vertices (z = 2), from inside
// the box, through sphere centres and grazing spheres, invalid rays.
void add_adversarial_rays(std::vector<QueryRay>& rays, const Scene& scene) {
    for (int x = -3; x <= 3; ++x)
        for (int y = -3; y <= 3; ++y) {
            rays.push_back(ray({x, y, -6}, {0, 0, 1}));           // through a vertex
            rays.push_back(ray({x, y + 0.5, 6}, {0, 0, -2}));     // through an edge
            rays.push_back(ray({x + 0.5, y, -6}, {0.0, 0.0, 3}));
            rays.push_back(ray({x - 0.25, y - 0.5, -6}, {0.125, 0.25, 2}));  // along a diagonal
        }
    for (int y = -3; y <= 3; ++y) rays.push_back(ray({-6, y, 2}, {1, 0, 0}));  // in the grid's plane, along edges
    std::mt19937 rng(5);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    for (int i = 0; i < 100; ++i) {  // from inside the box, some windows ending inside it
        const glm::dvec3 o(rnd(-1.4, 1.4), rnd(-1.4, 1.4), rnd(-0.9, 0.9)), d(rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
        rays.push_back(ray(o, d, 0.0f, i % 3 == 0 ? float(rnd(0.1, 1.0)) : kInf));
    }
    for (const Sphere& s : scene.spheres) {
        const glm::dvec3 c = s.center - kOffset, o = c + glm::dvec3(-7, 3, -5);
        rays.push_back(ray(o, c - o));                                          // both roots
        rays.push_back(ray(o, c + glm::dvec3(0, s.radius * 0.999999, 0) - o));  // grazing
        rays.push_back(ray(c, {0.3, -1, 0.2}));                                 // from the centre
    }
    const float nan = std::numeric_limits<float>::quiet_NaN();
    rays.push_back(ray({nan, 0, -6}, {0, 0, 1}));
    rays.push_back(ray({0, 0, -6}, {0, nan, 1}));
    rays.push_back(ray({0, 0, -6}, {0, 0, 0}));
    rays.push_back(ray({0, 0, -6}, {0, 0, 1}, 2.0f, 1.0f));
    rays.push_back(ray({0, 0, -6}, {0, 0, 1}, nan, kInf));
}

// aimed: with the rays aimed exactly at the grid's edges and vertices and at
// sphere silhouettes, whose hits turn on the last bit of the ray's move into
// the working frame: a device without fp64 moves it in float, an ulp away
// from the host's double at times, and its ray then passes by another side.
std::vector<QueryRay> hit_rays(const Scene& scene, bool aimed = true) {
    std::vector<QueryRay> rays;
    add_random_rays(rays, 11, 500);
    if (aimed) add_adversarial_rays(rays, scene);
    else add_random_rays(rays, 12, 300);
    return rays;
}

// What the OpenCL lists got against the cpu device's.
struct ListAgreement {
    int hits = 0, unexplained = 0, near_window = 0;
    std::string log;  // the first disagreements

    void unexplain(const std::string& what) {
        if (++unexplained <= 20) log += what + "\n";
    }
};

// Whether a hit at t may be in one list and not the other: OpenCL traces a
// ray with t_min > 0 from its advanced origin, so t rounds differently there.
bool near_window(const QueryRay& q, float t) {
    if (!(q.t_min > 0.0f)) return false;
    const double margin = 1e-4 * std::max(1.0, std::abs(double(t)));
    return std::abs(t - q.t_min) <= margin || std::abs(t - q.t_max) <= margin;
}

bool same_hit(const QueryHit& a, const QueryHit& b) {
    const float tol = 1e-5f * std::max(1.0f, std::abs(b.t));
    if (a.object != b.object || a.kind != b.kind || std::abs(a.t - b.t) > tol) return false;
    for (int k = 0; k < 3; ++k)
        if (std::abs(a.normal[k] - b.normal[k]) > 1e-4f) return false;
    return std::abs(a.u - b.u) <= 1e-4f && std::abs(a.v - b.v) <= 1e-4f;
}

// Ray i's lists: each OpenCL hit matched to one of the cpu device's; the
// unmatched ones on either side must lie at the window's edge.
void compare_ray(const QueryRay& q, std::span<const QueryHit> got, std::span<const QueryHit> want, ListAgreement& a,
                 std::size_t i) {
    std::vector<bool> used(want.size(), false);
    for (std::size_t k = 0; k < got.size(); ++k) {
        if (k > 0 && (got[k].t < got[k - 1].t || (got[k].t == got[k - 1].t && got[k].object < got[k - 1].object))) {
            a.unexplain("ray " + std::to_string(i) + ": OpenCL hit " + std::to_string(k) + " out of order");
        }
        std::size_t m = 0;
        while (m < want.size() && (used[m] || !same_hit(got[k], want[m]))) ++m;
        if (m < want.size()) used[m] = true;
        else if (near_window(q, got[k].t)) ++a.near_window;
        else a.unexplain("ray " + std::to_string(i) + ": OpenCL hit " + std::to_string(got[k].object) + " at " +
                         std::to_string(got[k].t) + " not on the cpu");
    }
    for (std::size_t m = 0; m < want.size(); ++m)
        if (!used[m] && !near_window(q, want[m].t))
            a.unexplain("ray " + std::to_string(i) + ": cpu hit " + std::to_string(want[m].object) + " at " +
                        std::to_string(want[m].t) + " not on OpenCL");
        else if (!used[m])
            ++a.near_window;
    a.hits += static_cast<int>(want.size());
}

// count_hits and all_hits on both sides; the counts equal the lists' lengths.
void check_hit_lists(const Pair& p, const std::vector<QueryRay>& rays) {
    std::vector<std::uint32_t> got_counts(rays.size(), 77), want_counts(rays.size());
    std::vector<std::uint64_t> got_splits, want_splits;
    std::vector<QueryHit> got, want;
    p.cl->count_hits(rays, got_counts);
    p.cl->all_hits(rays, got_splits, got);
    p.cpu->count_hits(rays, want_counts);
    p.cpu->all_hits(rays, want_splits, want);
    REQUIRE(got_splits.size() == rays.size() + 1);
    REQUIRE(got_splits.front() == 0);
    REQUIRE(got_splits.back() == got.size());
    ListAgreement a;
    int counts_differ = 0, long_lists = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const std::span<const QueryHit> g(got.data() + got_splits[i], got_splits[i + 1] - got_splits[i]);
        const std::span<const QueryHit> w(want.data() + want_splits[i], want_splits[i + 1] - want_splits[i]);
        CHECK(got_counts[i] == g.size());
        if (got_counts[i] != want_counts[i]) ++counts_differ;
        if (w.size() >= 3) ++long_lists;
        compare_ray(rays[i], g, w, a, i);
    }
    INFO(a.hits << " hits, " << a.near_window << " at a window's edge, " << counts_differ << " counts differ\n" << a.log);
    CHECK(a.unexplained == 0);
    CHECK(counts_differ <= a.near_window);
    CHECK(a.near_window <= a.hits / 100);
    CHECK(a.hits > static_cast<int>(rays.size()) / 2);
    CHECK(long_lists > static_cast<int>(rays.size()) / 20);  // rays that cross several objects
}

// Query points, and which lie at a sphere's centre: every point of the
// sphere is as near, and which is found turns on the last bit of the point's
// move into the working frame.
struct QueryPoints {
    std::vector<std::array<float, 3>> at;
    std::vector<bool> centre;
};

// Points near and far, on triangles and spheres, at sphere centres, on the
// grid's edges and vertices, inside the box, non-finite.
QueryPoints query_points(const Scene& scene) {
    std::mt19937 rng(23);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    std::vector<glm::dvec3> at;
    for (int i = 0; i < 400; ++i) {
        const double r = i % 4 == 0 ? 40.0 : 6.0;
        at.push_back(kOffset + glm::dvec3(rnd(-r, r), rnd(-r, r), rnd(-r, r)));
    }
    for (int i = 0; i < 20; ++i) at.push_back(kOffset + glm::dvec3(rnd(-1e4, 1e4), rnd(-1e4, 1e4), 2e4));
    std::vector<std::size_t> centres;
    for (const Sphere& s : scene.spheres) {
        centres.push_back(at.size());
        at.push_back(s.center);
        at.push_back(s.center + s.radius * glm::normalize(glm::dvec3(rnd(-1, 1), rnd(-1, 1), 0.5)));
    }
    const Mesh& loose = scene.triangles;
    for (std::size_t t = 0; t < loose.size(); t += 3) {
        const auto& v = loose.triangles[t].v;
        const double a = rnd(0, 0.5), b = rnd(0, 0.5);
        at.push_back((1 - a - b) * loose.positions[v[0]] + a * loose.positions[v[1]] + b * loose.positions[v[2]]);
    }
    for (int x = -3; x <= 3; ++x) {
        at.push_back(kOffset + glm::dvec3(x, 0.25, 2.5));
        at.push_back(kOffset + glm::dvec3(x, x, 2.0));
        at.push_back(kOffset + glm::dvec3(0.1 * x, 0.2, 0.1));  // inside the box
    }
    QueryPoints points;
    for (const glm::dvec3& q : at) points.at.push_back({float(q.x), float(q.y), float(q.z)});
    const float nan = std::numeric_limits<float>::quiet_NaN();
    points.at.push_back({nan, 0.0f, 0.0f});
    points.at.push_back({0.0f, kInf, 0.0f});
    points.centre.assign(points.at.size(), false);
    for (std::size_t i : centres) points.centre[i] = true;
    return points;
}

// Same object, or a tie (distances equal to float tolerance); distance and
// point to float tolerance; on the same object (away from a sphere's centre)
// point, normal and barycentrics too.
void check_closest_points(const Pair& p, const QueryPoints& points) {
    std::vector<ClosestPoint> got(points.at.size()), want(points.at.size());
    p.cl->closest_points(points.at, got);
    p.cpu->closest_points(points.at, want);
    int ties = 0, bad = 0;
    for (std::size_t i = 0; i < points.at.size(); ++i) {
        const ClosestPoint &g = got[i], &w = want[i];
        const double scale = std::max(1.0, double(w.distance));
        bool ok = g.object == w.object || std::abs(g.distance - w.distance) <= 1e-5 * scale;
        if (w.object == KDRT_NO_HIT) ok = g.object == KDRT_NO_HIT && std::isinf(g.distance) && std::isnan(g.point[0]);
        else ok = ok && std::abs(g.distance - w.distance) <= 1e-5 * scale + 1e-5;
        if (ok && w.object != KDRT_NO_HIT && g.object == w.object && !points.centre[i]) {
            for (int a = 0; a < 3; ++a) {
                ok &= std::abs(g.point[a] - w.point[a]) <= 1e-5 * (std::abs(w.point[a]) + scale);
                ok &= std::abs(g.normal[a] - w.normal[a]) <= 1e-4;
            }
            ok &= std::abs(g.u - w.u) <= 1e-4 && std::abs(g.v - w.v) <= 1e-4;
        }
        if (ok && g.object != w.object) ++ties;
        if (!ok) {
            ++bad;
            UNSCOPED_INFO("point " << i << ": OpenCL " << g.object << " at " << g.distance << ", cpu " << w.object
                                   << " at " << w.distance);
        }
    }
    INFO(ties << " ties of " << points.at.size() << " points");
    CHECK(bad == 0);
    CHECK(ties <= static_cast<int>(points.at.size()) / 20);
}

void check_all(DeviceBackend& device, Traversal traversal, Accel accel, Precision precision, bool aimed = true) {
    const Scene scene = hit_scene();
    const auto p = commit_pair(device, scene, options(traversal, accel, precision));
    check_hit_lists(*p, hit_rays(scene, aimed));
    check_closest_points(*p, query_points(scene));
}

}  // namespace

TEST_CASE("opencl hit lists: kd-trees, the BVH and no structure give the cpu device's hits and closest points",
          "[opencl][query][hit_lists]") {
    if (!have_opencl()) return;
    for (DeviceBackend* device : {&opencl_device(), &described_as_gpu()})
        for (auto [traversal, accel] : {std::pair{Traversal::Stack, Accel::KdTree}, {Traversal::ShortStack, Accel::KdTree},
                                        {Traversal::None, Accel::KdTree}, {Traversal::Stack, Accel::Bvh}}) {
            INFO((device == &opencl_device() ? "the device as it is" : "described as a GPU")
                 << ", " << to_string(traversal) << ", " << (accel == Accel::Bvh ? "BVH" : "kd-tree"));
            check_all(*device, traversal, accel, Precision::Float);
        }
}

TEST_CASE("opencl hit lists: double precision, and a device without doubles", "[opencl][query][hit_lists]") {
    if (!have_opencl()) return;
    if (opencl_device().info().fp64)
        for (Accel accel : {Accel::KdTree, Accel::Bvh}) {
            INFO("double, " << (accel == Accel::Bvh ? "BVH" : "kd-tree"));
            check_all(opencl_device(), Traversal::Stack, accel, Precision::Double);
        }
    INFO("no fp64, ropes");
    check_all(without_fp64(), Traversal::Ropes, Accel::KdTree, Precision::Float, false);
}

TEST_CASE("opencl hit lists: the public calls name hits and points as the cpu device does", "[opencl][query][hit_lists]") {
    if (!have_opencl()) return;
    const Scene scene = hit_scene();
    CommitOptions o = options(Traversal::Stack, Accel::KdTree, Precision::Float);
    const CommittedScene on_cl = CommittedScene::commit(Device::open("opencl"), scene, o);
    const CommittedScene on_cpu = CommittedScene::commit(Device::open("cpu"), scene, o);
    std::vector<QueryRay> rays = hit_rays(scene);
    std::erase_if(rays, [](const QueryRay& q) { return q.t_min > 0.0f; });  // no window's edge to tell apart
    const RayHitLists got = all_hits(on_cl, rays), want = all_hits(on_cpu, rays);
    REQUIRE(got.ray_splits == want.ray_splits);
    int named = 0;
    for (std::size_t k = 0; k < got.hits.size(); ++k) {
        CHECK(got.hits[k].object == want.hits[k].object);
        CHECK(got.hits[k].geometry == want.hits[k].geometry);
        CHECK(got.hits[k].primitive == want.hits[k].primitive);
        named += got.hits[k].primitive > 0;
    }
    CHECK(named > 0);
    const QueryPoints points = query_points(scene);
    std::vector<ClosestPoint> got_points(points.at.size()), want_points(points.at.size());
    closest_points(on_cl, points.at, got_points);
    closest_points(on_cpu, points.at, want_points);
    for (std::size_t i = 0; i < points.at.size(); ++i) {
        if (got_points[i].object != want_points[i].object) continue;  // a tie, checked above
        CHECK(got_points[i].geometry == want_points[i].geometry);
        CHECK(got_points[i].primitive == want_points[i].primitive);
    }
}

TEST_CASE("opencl hit lists: an empty scene has no hits and no closest points", "[opencl][query][hit_lists]") {
    if (!have_opencl()) return;
    const CommittedScene empty = CommittedScene::commit(Device::open("opencl"), Scene{});
    const std::vector<QueryRay> rays = {ray({0, 0, -6}, {0, 0, 1})};
    std::vector<std::uint32_t> counts(1, 7);
    count_hits(empty, rays, counts);
    CHECK(counts[0] == 0);
    CHECK(all_hits(empty, rays).hits.empty());
    const std::vector<std::array<float, 3>> points = {{{1, 2, 3}}};
    std::vector<ClosestPoint> out(1);
    closest_points(empty, points, out);
    CHECK(out[0].object == KDRT_NO_HIT);
    CHECK(std::isinf(out[0].distance));
    std::vector<QueryHit> hits(1);
    intersect(empty, rays, hits);
    CHECK(hits[0].object == KDRT_NO_HIT);
    CHECK(std::isinf(hits[0].t));
    std::vector<std::uint8_t> occluded_flags(1, 1);
    occluded(empty, rays, occluded_flags);
    CHECK(occluded_flags[0] == 0);
    // Nothing to trace: no kernels compiled for it (seconds on a cold cache).
    CHECK(empty.stats().compiles == 0);
}
