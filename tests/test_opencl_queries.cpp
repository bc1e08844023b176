// OpenCL ray queries and the persistent OpenCL device, on PoCL in CI: closest
// and any hits against a C++ brute force (every object through the C++
// intersection tests of src/cpu/intersect.h) for random and adversarial rays,
// every traversal of the kd-tree and the BVH's, float and double; queries
// into the application's own buffers on its own context; a second frame that
// neither compiles nor uploads geometry; cancellation; and the errors of the
// interop entry points. Skips with a warning without OpenCL.
#include "cpu/intersect.h"
#include "cpu/traversal_common.h"
#include "device/kernel_records.h"
#include "render/committed_scene_state.h"
#include "render/device_state.h"
#include "kdtree/tree_provider.h"
#include "have_opencl.h"
#include "walks.h"
#include "opencl/cl_devices.h"
#include "opencl/cl_query_staging.h"
#include "opencl/opencl_backend.h"
#include "opencl/kernel_variant.h"
#include "scene/prepared_scene.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/opencl_interop.h>
#include <kdrt/ray_query.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <thread>
#include <tuple>
#include <utility>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

using kdrt_test::have_opencl;

// The world offset makes the working frame's origin non-zero, so the
// world-to-frame translation of the rays is exercised.
const glm::dvec3 kOffset{100.0, -50.0, 20.0};

// Spheres and triangles with the hard cases of test_traversal.cpp: a grid of
// coplanar quads sharing edges and split planes, walls on the same planes,
// spheres touching each other, degenerate triangles.
Scene query_scene() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-4.0, 4.0), small(0.05, 0.6);
    std::uniform_int_distribution<int> grid(-4, 4);
    Scene s;
    auto m = s.add_material({});
    for (int i = 0; i < 20; ++i) s.add_sphere(kOffset + glm::dvec3{u(rng), u(rng), u(rng)}, small(rng), m);
    for (int i = 0; i < 6; ++i) s.add_sphere(kOffset + glm::dvec3(grid(rng), grid(rng), grid(rng)), 0.5, m);
    for (int i = 0; i < 50; ++i) {
        glm::dvec3 a = kOffset + glm::dvec3{u(rng), u(rng), u(rng)};
        s.add_triangle(a, a + glm::dvec3(small(rng), small(rng), u(rng) * 0.2),
                       a + glm::dvec3(-small(rng), small(rng), small(rng)), m);
    }
    for (int x = -3; x < 3; ++x)
        for (int y = -3; y < 3; ++y) {
            glm::dvec3 p = kOffset + glm::dvec3(x, y, 1.0);
            s.add_triangle(p, p + glm::dvec3(1, 0, 0), p + glm::dvec3(1, 1, 0), m);
            s.add_triangle(p, p + glm::dvec3(1, 1, 0), p + glm::dvec3(0, 1, 0), m);
        }
    for (int i = -2; i < 2; ++i) {
        s.add_triangle(kOffset + glm::dvec3(0, i, -2), kOffset + glm::dvec3(0, i + 1, -2),
                       kOffset + glm::dvec3(0, i + 1, 2), m);
        s.add_triangle(kOffset + glm::dvec3(i, 2, -2), kOffset + glm::dvec3(i + 1, 2, 2),
                       kOffset + glm::dvec3(i, 2, 2), m);
    }
    s.add_triangle(kOffset + glm::dvec3(0, 0, 0), kOffset + glm::dvec3(1, 1, 1), kOffset + glm::dvec3(2, 2, 2), m);
    s.camera.position = kOffset + glm::dvec3(0, 0, -12);
    s.camera.look_at = kOffset;
    s.add_light({kOffset + glm::dvec3(3, 6, -8), glm::dvec3(1.0)});
    s.settings.width = s.settings.height = 48;
    return s;
}

// The one OpenCL device of the test run, and the scenes committed on it: one
// per traversal and precision (each costs a kernel compile on PoCL).
DeviceBackend& opencl_device() {
    static std::unique_ptr<DeviceBackend> device = make_opencl_backend(ocl::select_device("opencl"));
    return *device;
}

struct Committed {
    Scene scene;
    PreparedScene prepared;
    std::shared_ptr<const KdTree> tree;
    std::shared_ptr<const WideBvh> bvh;  // with Accel::Bvh
    RenderOptions options;
    BackendWork work;
    std::unique_ptr<SceneBackend> backend;
    const KdTree* kd() const { return tree.get(); }
    AccelRef accel() const { return {tree.get(), bvh.get()}; }
};

RenderOptions query_options(Traversal traversal, Precision precision, Accel accel = Accel::KdTree) {
    RenderOptions o;
    o.commit.accel = accel;
    o.commit.traversal = traversal;
    o.commit.accuracy.precision = precision;
    o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    return o;
}

std::unique_ptr<Committed> commit_on(DeviceBackend& device, const Scene& scene, const RenderOptions& options) {
    auto c = std::make_unique<Committed>();
    c->scene = scene;
    c->options = options;
    c->prepared = prepare_scene(c->scene, options.commit, options.frame);
    if (options.commit.traversal != Traversal::None) {
        if (options.commit.accel == Accel::Bvh) c->bvh = provide_bvh(c->prepared, options.commit).bvh;
        else c->tree = provide_tree(c->prepared, options.commit).tree;
    }
    c->backend = device.commit(c->prepared, c->accel(), options.commit, c->work);
    return c;
}

Committed& committed(Traversal traversal, Precision precision, Accel accel = Accel::KdTree) {
    static std::map<std::tuple<Traversal, Precision, Accel>, std::unique_ptr<Committed>> scenes;
    auto& c = scenes[{traversal, precision, accel}];
    if (!c) c = commit_on(opencl_device(), query_scene(), query_options(traversal, precision, accel));
    return *c;
}

// The OpenCL device described as a GPU with memory of its own: it then gets
// the kernels a GPU gets, without a CPU device's code (KDRT_CPU_DEVICE), and
// its host queries go through staging buffers. cpu_code: whether the device
// itself is a CPU device (PoCL), whose kernels have that code.
DeviceBackend& described_as_gpu(bool& cpu_code) {
    static bool cpu = false;
    static const std::unique_ptr<DeviceBackend> device = [] {
        ocl::ClDevice d = ocl::select_device("opencl");
        cpu = d.info.type == "cpu";
        d.info.type = "gpu";
        d.host_memory = false;
        return make_opencl_backend(d);
    }();
    cpu_code = cpu;
    if (!cpu) WARN("the OpenCL device is no CPU device: both sides run the kernels a GPU gets");
    return *device;
}

QueryRay query_ray(const glm::dvec3& o, const glm::dvec3& d, float t_min = 0.0f,
                   float t_max = std::numeric_limits<float>::infinity()) {
    QueryRay r{};
    for (int a = 0; a < 3; ++a) {
        r.origin[a] = static_cast<float>(o[a]);
        r.direction[a] = static_cast<float>(d[a]);
    }
    r.t_min = t_min;
    r.t_max = t_max;
    return r;
}

// Random and adversarial rays in world space, with unnormalised directions.
// `aimed`: also rays aimed exactly at shared edges and vertices and grazing
// spheres to 1e-6 of their radius, whose answer turns on the last bit of the
// origin's move into the working frame.
std::vector<QueryRay> adversarial_rays(const PreparedScene& p, AccelRef accel, std::uint32_t seed,
                                       bool aimed = true) {
    const KdTree* tree = accel.kd;
    std::mt19937 rng(seed);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    const glm::dvec3 lo = p.bounds.lo + p.frame_origin, hi = p.bounds.hi + p.frame_origin;
    const glm::dvec3 pad = 0.5 * (hi - lo);
    auto point = [&](bool inside) {
        const glm::dvec3 l = inside ? lo : lo - pad, h = inside ? hi : hi + pad;
        return glm::dvec3(rnd(l.x, h.x), rnd(l.y, h.y), rnd(l.z, h.z));
    };
    auto dir = [&] {
        glm::dvec3 d;
        do d = glm::dvec3(rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
        while (glm::length(d) < 0.1);
        return d * rnd(0.1, 10.0);  // any length: t is in its units
    };
    std::vector<QueryRay> rays;
    for (int i = 0; i < 300; ++i) {
        const glm::dvec3 o = point(i % 2 == 0);
        rays.push_back(query_ray(o, point(true) - o));
        rays.push_back(query_ray(o, dir()));
    }
    // Windows: starting inside objects, ending before them, empty, reversed.
    for (int i = 0; i < 300; ++i) {
        const glm::dvec3 o = point(i % 2 == 0);
        const float t_min = static_cast<float>(rnd(0.0, 1.0)), t_max = t_min + static_cast<float>(rnd(0.0, 1.5));
        rays.push_back(query_ray(o, point(true) - o, t_min, t_max));
    }
    rays.push_back(query_ray(point(true), dir(), 0.5f, 0.5f));
    rays.push_back(query_ray(point(true), dir(), 0.7f, 0.2f));
    rays.push_back(query_ray(point(true), glm::dvec3(0.0), 0.0f, 1.0f));
    // Axis-parallel rays.
    for (int i = 0; i < 60; ++i) {
        glm::dvec3 d(0.0);
        d[i % 3] = (i & 8) ? 2.0 : -0.5;
        rays.push_back(query_ray(point(i % 3 != 0), d));
    }
    // Rays lying in split planes and starting on them.
    if (tree)
        for (std::size_t n = 0, taken = 0; n < tree->nodes.size() && taken < 80; ++n) {
            const KdNode node = tree->nodes[n];
            if (kd_is_leaf(node)) continue;
            ++taken;
            const int axis = kd_axis(node);
            glm::dvec3 o = point(true);
            o[axis] = static_cast<double>(kd_split(node)) + p.frame_origin[axis];
            glm::dvec3 d = dir();
            d[axis] = 0.0;
            rays.push_back(query_ray(o, d));
            rays.push_back(query_ray(o, dir()));
        }
    // Rays lying in the BVH's box planes (a NaN slab distance) and starting on them.
    if (accel.bvh)
        for (std::size_t n = 0, taken = 0; n < accel.bvh->nodes.size() && taken < 80; ++n) {
            const WideBvhNode& node = accel.bvh->nodes[n];
            for (int slot = 0; slot < kWideBvhWidth && taken < 80; ++slot, ++taken) {
                if (node.count[slot] == kBvhLeafFlag) break;  // empty slots follow the used ones
                const int axis = static_cast<int>(taken % 3);
                glm::dvec3 o = point(true);
                o[axis] = static_cast<double>(node.box[taken % 2][axis][slot]) + p.frame_origin[axis];
                glm::dvec3 d = dir();
                d[axis] = 0.0;
                rays.push_back(query_ray(o, d));
                rays.push_back(query_ray(o, dir()));
            }
        }
    // Into faces lying in a coordinate plane, where a kd-tree splits: each ray's
    // hit and a split plane's t are the same plane's distance, rounded two ways.
    const auto& g = p.geometry_f;
    for (const auto& t : g.triangles)
        for (int a = 0; a < 3; ++a) {
            if (t.v0[a] != t.v1[a] || t.v0[a] != t.v2[a]) continue;
            for (int k = 0; k < 4; ++k) {
                const double b1 = rnd(0.05, 0.9), b2 = rnd(0.05, 0.95 - b1);
                const glm::dvec3 at = glm::dvec3(t.v0) + b1 * glm::dvec3(t.v1 - t.v0) + b2 * glm::dvec3(t.v2 - t.v0);
                const glm::dvec3 o = point(false);
                rays.push_back(query_ray(o, at + p.frame_origin - o));
                rays.push_back(query_ray(o, glm::normalize(at + p.frame_origin - o)));
            }
        }
    if (!aimed) return rays;
    // Through shared edges and vertices of the quad grid, and grazing spheres.
    for (std::size_t i = 0; i < g.triangles.size(); i += 2) {
        const auto& t = g.triangles[i];
        const glm::dvec3 edge = 0.5 * (glm::dvec3(t.v0) + glm::dvec3(t.v2)) + p.frame_origin;
        const glm::dvec3 o = point(false);
        rays.push_back(query_ray(o, edge - o));
        rays.push_back(query_ray(o, glm::dvec3(t.v0) + p.frame_origin - o));
    }
    for (const auto& s : g.spheres) {
        const glm::dvec3 c = glm::dvec3(s.center) + p.frame_origin;
        for (double k : {1.0 - 1e-6, 1.0, 1.0 + 1e-6}) {
            const glm::dvec3 o = c + glm::dvec3(-3.0 * s.radius, k * s.radius, 0.0);
            rays.push_back(query_ray(o, glm::dvec3(1.0, 0.0, 0.0)));
        }
    }
    return rays;
}

// The brute force: every object through intersect.h, on the working ray the
// host's queries use (origin - frame_origin and normalisation in double), the
// window applied to t / |direction| with both sphere roots as candidates.
template <class Real>
Hit<Real> brute_force(const PreparedScene& p, const QueryRay& q, double* length) {
    using Vec = glm::vec<3, Real>;
    Hit<Real> best;
    const glm::dvec3 o(q.origin[0], q.origin[1], q.origin[2]), d(q.direction[0], q.direction[1], q.direction[2]);
    *length = glm::length(d);
    if (!(*length > 0.0) || !(q.t_min <= q.t_max)) return best;
    const Ray<Real> ray(Vec(o - p.frame_origin), Vec(d / *length));
    const auto& g = p.geometry<Real>();
    auto inside = [&](Real t) {
        const double tq = static_cast<double>(t) / *length;
        return t > Real(0) && tq > q.t_min && tq <= q.t_max;
    };
    for (std::uint32_t id = 0; id < g.object_count(); ++id) {
        Hit<Real> h;
        h.id = static_cast<std::int32_t>(id);
        if (id < g.spheres.size()) {
            Real t0, t1;
            if (!sphere_roots(ray, g.spheres[id].center, g.spheres[id].radius, t0, t1)) continue;
            if (inside(t0)) h.t = t0;
            else if (inside(t1)) h.t = t1;
            else continue;
        } else {
            const auto& t = g.triangles[id - g.spheres.size()];
            if (!intersect_triangle(ray, t.v0, t.v1, t.v2, h.t, h.b1, h.b2) || !inside(h.t)) continue;
        }
        if (h.closer_than(best.t, best.id)) best = h;
    }
    return best;
}

struct Agreement {
    int rays = 0, hits = 0, exact = 0, explained = 0, unexplained = 0;
};

// Closest hits against the brute force. A different answer is explained only
// by a tie (two objects at the same t: shared edges, touching spheres) or, in
// a window starting at t_min > 0 (traced from an advanced origin), by a hit
// within rounding of the window's ends.
template <class Real>
Agreement compare_closest(const PreparedScene& p, const std::vector<QueryRay>& rays, const std::vector<QueryHit>& got) {
    Agreement a;
    const double tol = sizeof(Real) == 4 ? 2e-5 : 1e-10;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        double length = 0.0;
        const Hit<Real> bf = brute_force<Real>(p, rays[i], &length);
        const QueryHit& h = got[i];
        ++a.rays;
        const double t_bf = bf.valid() ? static_cast<double>(bf.t) / length : 0.0;
        const double scale = std::max(1.0, std::abs(t_bf)) * std::max(1.0, length);
        if (!bf.valid() && h.object == KDRT_NO_HIT) {
            ++a.exact;
            continue;
        }
        if (bf.valid() && h.object == static_cast<std::uint32_t>(bf.id)) {
            ++a.hits;
            const bool sphere = static_cast<std::uint32_t>(bf.id) < p.geometry_f.spheres.size();
            const double n_len = std::sqrt(double(h.normal[0]) * h.normal[0] + double(h.normal[1]) * h.normal[1] +
                                           double(h.normal[2]) * h.normal[2]);
            const bool ok = std::abs(h.t - t_bf) <= 2e-5 * scale + tol * scale &&
                            h.kind == (sphere ? KDRT_KIND_SPHERE : KDRT_KIND_TRIANGLE) && std::abs(n_len - 1.0) < 1e-4 &&
                            (sphere || (std::abs(h.u - float(bf.b1)) < 1e-4 && std::abs(h.v - float(bf.b2)) < 1e-4));
            if (ok) ++a.exact;
            else {
                ++a.unexplained;
                UNSCOPED_INFO("ray " << i << ": same object " << h.object << " but t " << h.t << " vs " << t_bf
                                     << ", u " << h.u << " vs " << bf.b1 << ", |n| " << n_len);
            }
            continue;
        }
        const bool windowed = rays[i].t_min > 0.0f;
        const double near_edge = 1e-4 * scale;
        bool explained = false;
        if (bf.valid() && h.object != KDRT_NO_HIT && std::abs(h.t - t_bf) <= near_edge) explained = true;  // a tie
        if (windowed) {
            for (double t : {bf.valid() ? t_bf : -1.0, h.object != KDRT_NO_HIT ? double(h.t) : -1.0})
                if (t >= 0.0 && (std::abs(t - rays[i].t_min) <= near_edge || std::abs(t - rays[i].t_max) <= near_edge))
                    explained = true;
        }
        if (explained) ++a.explained;
        else {
            ++a.unexplained;
            UNSCOPED_INFO("ray " << i << ": brute force " << (bf.valid() ? bf.id : -1) << " at " << t_bf
                                 << ", OpenCL " << static_cast<std::int64_t>(h.object == KDRT_NO_HIT ? -1 : h.object)
                                 << " at " << h.t);
        }
    }
    return a;
}

// Rays whose windows end at their closest hits (h: the device's answers for
// rays): to the float (t_max = t), an ulp before it and an ulp past it. The
// ulp past must find the same hit, the ulp before none (it was the closest).
struct WindowEdges {
    std::vector<QueryRay> at, before, past;
    std::vector<std::size_t> from;  // the ray each was made from
};

WindowEdges window_edges(const std::vector<QueryRay>& rays, const std::vector<QueryHit>& h) {
    WindowEdges e;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        if (h[i].object == KDRT_NO_HIT || rays[i].t_min > 0.0f) continue;
        QueryRay r = rays[i];
        e.from.push_back(i);
        r.t_max = h[i].t;
        e.at.push_back(r);
        r.t_max = std::nextafter(h[i].t, 0.0f);
        e.before.push_back(r);
        r.t_max = std::nextafter(h[i].t, std::numeric_limits<float>::infinity());
        e.past.push_back(r);
    }
    return e;
}

// Any hit must say what the closest hit says, for every ray: the closest hit
// is inside the window exactly when some hit is, windows ending at a hit's t
// or an ulp from it included.
int unlike_closest(const std::vector<QueryRay>& rays, const std::vector<std::uint8_t>& got,
                   const std::vector<QueryHit>& closest) {
    int bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const bool hit = closest[i].object != KDRT_NO_HIT;
        if (got[i] == (hit ? 1 : 0)) continue;
        ++bad;
        UNSCOPED_INFO("ray " << i << ": occluded " << int(got[i]) << ", closest hit " << closest[i].object << " at "
                             << std::hexfloat << closest[i].t << " in (" << rays[i].t_min << ", " << rays[i].t_max
                             << "]" << std::defaultfloat);
    }
    return bad;
}

void check_window_edges(Committed& c, const std::vector<QueryRay>& rays, const std::vector<QueryHit>& hits) {
    const WindowEdges e = window_edges(rays, hits);
    CHECK(e.at.size() > rays.size() / 8);
    int at_hits = 0;
    for (const std::vector<QueryRay>* edge : {&e.at, &e.before, &e.past}) {
        std::vector<QueryHit> h(edge->size());
        std::vector<std::uint8_t> occluded(edge->size(), 7);
        c.backend->intersect(*edge, h);
        c.backend->occluded(*edge, occluded);
        CHECK(unlike_closest(*edge, occluded, h) == 0);
        int wrong = 0;
        for (std::size_t k = 0; k < edge->size(); ++k) {
            const QueryHit& was = hits[e.from[k]];
            const bool ok = edge == &e.before ? h[k].object == KDRT_NO_HIT
                            : edge == &e.past ? h[k].object == was.object && h[k].t == was.t
                                              : h[k].object == KDRT_NO_HIT || h[k].object == was.object;
            at_hits += edge == &e.at && h[k].object != KDRT_NO_HIT;
            if (!ok) {
                ++wrong;
                UNSCOPED_INFO("ray " << e.from[k] << " ending at " << std::hexfloat << (*edge)[k].t_max << ": "
                                     << h[k].object << " at " << h[k].t << ", was " << was.object << " at " << was.t
                                     << std::defaultfloat);
            }
        }
        CHECK(wrong == 0);
    }
    INFO(at_hits << " of " << e.at.size() << " rays ending at their hits' t keep them");
    CHECK(at_hits > 0);
}

template <class Real>
void check_queries(Committed& c, bool aimed = true) {
    const std::vector<QueryRay> rays = adversarial_rays(c.prepared, c.accel(), 11, aimed);
    std::vector<QueryHit> hits(rays.size());
    std::vector<std::uint8_t> occluded(rays.size(), 7);
    c.backend->intersect(rays, hits);
    c.backend->occluded(rays, occluded);
    const Agreement a = compare_closest<Real>(c.prepared, rays, hits);
    INFO(a.rays << " rays, " << a.hits << " hits, " << a.exact << " exact, " << a.explained << " explained");
    CHECK(a.unexplained == 0);
    CHECK(a.explained <= a.rays / 50);
    CHECK(a.hits > a.rays / 4);  // the rays do hit things
    CHECK(unlike_closest(rays, occluded, hits) == 0);
    check_window_edges(c, rays, hits);
}

}  // namespace

TEST_CASE("opencl queries: closest and any hits agree with brute force", "[opencl][query]") {
    if (!have_opencl()) return;
    for (Precision precision : {Precision::Float, Precision::Double}) {
        if (precision == Precision::Double && !opencl_device().info().fp64) continue;
        for (Traversal traversal : {Traversal::None, Traversal::Restart, Traversal::Ropes, Traversal::Stack, Traversal::ShortStack}) {
            INFO(to_string(traversal) << ", " << to_string(precision));
            Committed& c = committed(traversal, precision);
            if (precision == Precision::Double) check_queries<double>(c);
            else check_queries<float>(c);
        }
    }
}

// A grid of axis-aligned cubes: every face lies in a plane a kd-tree splits at.
Scene cubes_scene() {
    Scene s;
    auto m = s.add_material({});
    s.add_sphere(kOffset + glm::dvec3(0.0, 0.0, 6.0), 0.5, m);
    for (int x = -3; x < 3; ++x)
        for (int y = -3; y < 3; ++y)
            for (int z = -1; z < 2; ++z) {
                const glm::dvec3 lo = kOffset + glm::dvec3(x, y, z) * 1.25, hi = lo + glm::dvec3(0.75, 0.5, 1.0);
                auto corner = [&](int i) { return glm::dvec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z); };
                for (int a = 0; a < 3; ++a)
                    for (int side = 0; side < 2; ++side) {
                        const int b = 1 << a, c = 1 << (a + 1) % 3, d = 1 << (a + 2) % 3, o = side ? b : 0;
                        s.add_triangle(corner(o), corner(o | c), corner(o | c | d), m);
                        s.add_triangle(corner(o), corner(o | c | d), corner(o | d), m);
                    }
            }
    s.camera.position = kOffset + glm::dvec3(0, 0, -12);
    s.camera.look_at = kOffset;
    s.add_light({kOffset + glm::dvec3(3, 6, -8), glm::dvec3(1.0)});
    s.settings.width = s.settings.height = 16;
    return s;
}

using kdrt_test::kPrunedWalks;  // the kd-tree's four pruning traversals and the BVH's

// check(device, options) for every pruning walk, in both precisions, on the
// device as it is and described as a GPU.
template <class Check>
void for_each_pruned_walk(Check&& check) {
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    for (DeviceBackend* device : {&opencl_device(), &gpu_device})
        for (Precision precision : {Precision::Float, Precision::Double}) {
            if (precision == Precision::Double && !opencl_device().info().fp64) continue;
            for (const auto& [accel, traversal] : kPrunedWalks) {
                INFO((device == &gpu_device ? "described as a GPU" : "the device as it is")
                     << ", " << to_string(accel) << ", " << to_string(traversal) << ", " << to_string(precision));
                check(*device, query_options(traversal, precision, accel));
            }
        }
}

TEST_CASE("opencl queries: windows ending at hits on faces in split planes", "[opencl][query]") {
    if (!have_opencl()) return;
    for_each_pruned_walk([](DeviceBackend& device, RenderOptions o) {
        o.commit.tree.builder = KdBuilderKind::SahExact;  // splits at the faces' planes
        const auto c = commit_on(device, cubes_scene(), o);
        const std::vector<QueryRay> rays = adversarial_rays(c->prepared, c->accel(), 15, false);
        std::vector<QueryHit> hits(rays.size());
        std::vector<std::uint8_t> occluded(rays.size(), 7);
        c->backend->intersect(rays, hits);
        c->backend->occluded(rays, occluded);
        const Agreement a = o.commit.accuracy.precision == Precision::Double
                                ? compare_closest<double>(c->prepared, rays, hits)
                                : compare_closest<float>(c->prepared, rays, hits);
        INFO(a.rays << " rays, " << a.hits << " hits, " << a.explained << " explained");
        CHECK(a.unexplained == 0);
        CHECK(unlike_closest(rays, occluded, hits) == 0);
        check_window_edges(*c, rays, hits);
    });
}

// Two parallel triangles 4 ulps apart in one leaf, the farther one first
// (ids ascend in a leaf), and windows ending between them: the any-hit walk,
// bounded a little past the window's end, stops at the farther one, outside,
// and the closest hit, inside, must answer.
TEST_CASE("opencl queries: an any-hit walk stopped just past the window's end asks the closest hit", "[opencl][query]") {
    if (!have_opencl()) return;
    Scene scene;
    const auto m = scene.add_material({});
    const double far_z = 1.0 + 4.0 * std::numeric_limits<float>::epsilon();
    for (double z : {far_z, 1.0})
        scene.add_triangle(glm::dvec3(-1.0, -1.0, z), glm::dvec3(1.0, -1.0, z), glm::dvec3(0.0, 1.0, z), m);
    scene.camera.position = glm::dvec3(0.0, 0.0, -3.0);
    scene.camera.look_at = glm::dvec3(0.0);
    scene.add_light({glm::dvec3(0.0, 0.0, -3.0), glm::dvec3(1.0)});
    scene.settings.width = scene.settings.height = 8;
    std::vector<QueryRay> rays;
    for (double x : {-0.3, -0.1, 0.0, 0.2, 0.3})
        for (double y : {-0.5, -0.2, 0.1, 0.2})  // inside both triangles
            rays.push_back(query_ray(glm::dvec3(x, y, 0.0), glm::dvec3(0.0, 0.0, 1.0), 0.0f,
                                     1.0f + 2.0f * std::numeric_limits<float>::epsilon()));
    for_each_pruned_walk([&](DeviceBackend& device, const RenderOptions& o) {
        const auto c = commit_on(device, scene, o);
        std::vector<QueryHit> hits(rays.size());
        std::vector<std::uint8_t> occluded(rays.size(), 7);
        c->backend->intersect(rays, hits);
        c->backend->occluded(rays, occluded);
        for (std::size_t i = 0; i < rays.size(); ++i) {
            INFO("ray " << i);
            CHECK(hits[i].object == 1u);  // the nearer triangle
            CHECK(occluded[i] == 1);
        }
    });
}

TEST_CASE("opencl queries: a device without doubles agrees with brute force", "[opencl][query]") {
    if (!have_opencl()) return;
    // The same device described as one without fp64: the kernels then move
    // rays into the working frame with a float pair and normalise in float,
    // an ulp away from the host's double at times: rays aimed at edges
    // exactly can then take the other side.
    ocl::ClDevice no_fp64 = ocl::select_device("opencl");
    no_fp64.info.fp64 = false;
    static const std::unique_ptr<DeviceBackend> device = make_opencl_backend(no_fp64);
    const auto c = commit_on(*device, query_scene(), query_options(Traversal::Stack, Precision::Float));
    CHECK(c->backend->render(c->options.frame).stats.opencl.kernel_options.find("KDRT_HAS_FP64") == std::string::npos);
    check_queries<float>(*c, false);
}

TEST_CASE("opencl: a CPU device's packets and lanes render the GPU kernels' pictures bit for bit",
          "[opencl][render][lanes][slow]") {
    if (!have_opencl()) return;
    // On a CPU device the stack traversal's renders trace four rays per
    // work-item as a packet (traverse_packet.cl) and test leaves four
    // triangles at a time; described as a GPU, the same device runs the
    // plain kernels. Pixel sums are fixed point, so equal rays give equal
    // pictures whatever the order: ids, distances and colours must match exactly.
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"}) {
        for (Precision precision : {Precision::Float, Precision::Double}) {
            // Double on the scenes with triangles and with glass (CI time: each variant compiles twice).
            const bool doubles = std::string(name) == "insane" || std::string(name) == "lens";
            if (precision == Precision::Double && (!doubles || !opencl_device().info().fp64)) continue;
            INFO(name << ", " << to_string(precision));
            RenderOptions o = query_options(Traversal::Stack, precision);
            o.frame.width = 71;  // 3763 pixels: the last packet of a batch is partial
            o.frame.height = 53;
            o.frame.want_ids = true;
            const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
            const auto cpu = commit_on(opencl_device(), scene, o);
            const auto gpu = commit_on(gpu_device, scene, o);
            const RenderResult a = cpu->backend->render(o.frame), b = gpu->backend->render(o.frame);
            CHECK((a.stats.opencl.kernel_options.find("-DKDRT_CPU_DEVICE") != std::string::npos) == cpu_code);
            CHECK((a.stats.opencl.kernel_options.find("-DKDRT_PACKETS=4") != std::string::npos) == cpu_code);
            CHECK(b.stats.opencl.kernel_options.find("KDRT_CPU_DEVICE") == std::string::npos);
            CHECK(a.ids == b.ids);
            CHECK(a.hit_t == b.hit_t);
            CHECK(a.image.rgb == b.image.rgb);
            CHECK(a.stats.rays.total() == b.stats.rays.total());
            CHECK(std::count(a.ids.begin(), a.ids.end(), -1) < static_cast<std::ptrdiff_t>(a.ids.size()));
            // Three samples: the sums of each pixel's three ray trees.
            RenderOptions samples = o;
            samples.frame.samples = 3;
            const RenderResult a3 = commit_on(opencl_device(), scene, samples)->backend->render(samples.frame),
                               b3 = commit_on(gpu_device, scene, samples)->backend->render(samples.frame);
            CHECK(a3.ids == b3.ids);
            CHECK(a3.image.rgb == b3.image.rgb);
            CHECK((a3.image.rgb != a.image.rgb));
        }
    }
}

TEST_CASE("opencl: a GPU's computed ray orders give the CPU device's pictures", "[opencl][render]") {
    if (!have_opencl()) return;
    // A GPU's frame kernel computes rows and tiles (pixel_at, render.cl); a
    // CPU device's reads the host's table (ray_order.cpp). A pixel traced
    // twice or never changes the picture; sizes with partial edge tiles.
    // purple-wall has no bounces: its kernels write the image themselves
    // (to_pixel), into the buffer a frame of a smaller region filled first,
    // so a pixel never written keeps another pixel's value.
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    for (const char* name : {"2x2x4", "purple-wall"}) {
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        for (const auto& [w, h] : {std::pair{71, 53}, std::pair{5, 19}, std::pair{16, 8}})
            for (RayOrder order : {RayOrder::Rows, RayOrder::Tiles, RayOrder::Morton}) {
                INFO(name << ", " << w << "x" << h << ", " << to_string(order));
                RenderOptions o = query_options(Traversal::Stack, Precision::Float);
                o.frame.width = w;
                o.frame.height = h;
                o.frame.opencl.ray_order = order;
                o.frame.want_ids = true;
                RenderOptions inner = o;
                inner.frame.region = PixelRect{1, 1, w - 1, h - 1};
                const auto cpu = commit_on(opencl_device(), scene, o);
                const auto gpu = commit_on(gpu_device, scene, o);
                const RenderResult before = gpu->backend->render(inner.frame);
                CHECK(before.image.width == w - 1);
                const RenderResult a = cpu->backend->render(o.frame), b = gpu->backend->render(o.frame);
                CHECK(a.ids == b.ids);
                CHECK(a.image.rgb == b.image.rgb);
            }
    }
}

TEST_CASE("opencl: bounce levels chained on a GPU give the picture of levels read one by one", "[opencl][render]") {
    if (!have_opencl()) return;
    // On a GPU a camera batch's bounce levels are launched back to back and
    // the counters read once (cl_frame_renderer.cpp, chain); a CPU device
    // reads them after every launch. A glass ball that fills the view makes
    // two rays of every camera ray, a full queue at the first bounce: half of
    // it waits in its queue and is traced after the chain.
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    Scene scene;
    const MaterialId glass = scene.add_material({.name = "glass", .color = {0.9, 0.9, 1.0}, .diffuse = 0.2, .reflect = 0.4, .transmit = 0.6});
    const MaterialId wall = scene.add_material({.name = "wall", .color = {0.8, 0.3, 0.2}});
    scene.add_sphere({0.0, 0.0, 0.0}, 1.0, glass);
    for (int i = 0; i < 5; ++i) scene.add_sphere({-2.0 + i, -1.5, 2.5}, 0.6, wall);
    scene.add_light({{2.0, 3.0, -4.0}, glm::dvec3(1.0)});
    scene.camera.position = {0.0, 0.0, -1.9};
    scene.camera.look_at = {0.0, 0.0, 0.0};
    scene.camera.fov_y = 30.0;
    (void)cpu_code;
    RenderOptions o = query_options(Traversal::Stack, Precision::Float);
    o.frame.width = o.frame.height = 64;  // one camera batch
    o.frame.want_ids = true;
    RenderOptions plain = o;  // the plain schedule reads after every launch on any device
    plain.frame.opencl.schedule = Schedule::Plain;
    o.frame.opencl.profile_commands = true;
    const auto one_by_one = commit_on(opencl_device(), scene, plain);
    const auto chained = commit_on(gpu_device, scene, o);
    const RenderResult a = one_by_one->backend->render(plain.frame), b = chained->backend->render(o.frame);
    CHECK(std::count(a.ids.begin(), a.ids.end(), 0) == static_cast<std::ptrdiff_t>(a.ids.size()));  // all glass
    std::uint64_t reads = 0;
    for (const CommandTime& c : b.stats.opencl.command_times) reads += c.command == "read counters" ? c.count : 0;
    CHECK(reads < static_cast<std::uint64_t>(b.stats.opencl.launches));                          // chained: fewer reads than launches
    CHECK(b.stats.opencl.launches > scene.settings.max_depth);        // one chain, then the rest of a full queue
    CHECK(a.ids == b.ids);
    CHECK(a.hit_t == b.hit_t);
    CHECK(a.image.rgb == b.image.rgb);
    CHECK(a.stats.rays.shadow == b.stats.rays.shadow);
    CHECK(a.stats.rays.secondary == b.stats.rays.secondary);
    CHECK(a.stats.rays.secondary > 2 * a.stats.rays.camera);
}

TEST_CASE("opencl queries: four triangles at a time give the one-at-a-time kernels' hits bit for bit",
          "[opencl][query][lanes]") {
    if (!have_opencl()) return;
    // PoCL is a CPU device: its kernels test a leaf's triangles four at a
    // time (KDRT_CPU_DEVICE); a single ray's closest and any hits from the packed
    // leaves' blocks (KDRT_PACKED_LEAVES, not with Traversal::None), packets
    // from the leaves' lists. The same device described as a GPU gets the
    // kernels a GPU gets, one triangle at a time: both must find the same hits.
    bool lanes = false;
    DeviceBackend& gpu_device = described_as_gpu(lanes);
    for (Precision precision : {Precision::Float, Precision::Double}) {
        if (precision == Precision::Double && !opencl_device().info().fp64) continue;
        for (Traversal traversal : {Traversal::None, Traversal::Ropes, Traversal::Stack}) {
            INFO(to_string(traversal) << ", " << to_string(precision));
            Committed& four = committed(traversal, precision);
            const auto one = commit_on(gpu_device, query_scene(), query_options(traversal, precision));
            const std::string four_kernel = four.backend->render(four.options.frame).stats.opencl.kernel_options;
            CHECK((four_kernel.find("-DKDRT_CPU_DEVICE") != std::string::npos) == lanes);
            CHECK((four_kernel.find("-DKDRT_PACKED_LEAVES") != std::string::npos) ==
                  (lanes && traversal != Traversal::None));
            CHECK(one->backend->render(one->options.frame).stats.opencl.kernel_options.find("KDRT_CPU_DEVICE") == std::string::npos);
            if (traversal == Traversal::Stack) {
                // Leaves of four or more triangles, so that full batches are tested.
                std::uint32_t most = 0;
                for (const KdNode& n : four.kd()->nodes)
                    if (kd_is_leaf(n)) most = std::max(most, kd_leaf_count(n));
                CHECK(most >= 4);
            }
            std::vector<QueryRay> rays = adversarial_rays(four.prepared, four.kd(), 13);
            // Coherent bundles, so that four consecutive rays form packets
            // (the stack traversal's): a grid from beyond the box's low
            // corner over the scene, whole rays and windows by fours.
            const glm::dvec3 lo = four.prepared.bounds.lo + four.prepared.frame_origin,
                             hi = four.prepared.bounds.hi + four.prepared.frame_origin;
            const glm::dvec3 eye = lo - 0.6 * (hi - lo);
            for (int y = 0; y < 24; ++y)
                for (int x = 0; x < 24; ++x) {
                    const glm::dvec3 d =
                        glm::dvec3(lo.x + (hi.x - lo.x) * (x + 0.5) / 24.0, lo.y + (hi.y - lo.y) * (y + 0.5) / 24.0, hi.z) -
                        eye;
                    const int window = (y * 24 + x) / 4 % 3;
                    rays.push_back(window == 0   ? query_ray(eye, d)
                                   : window == 1 ? query_ray(eye, d, 0.9f)
                                                 : query_ray(eye, d, 0.0f, 1.1f));
                }
            std::vector<QueryHit> a(rays.size()), b(rays.size());
            std::vector<std::uint8_t> blocked_a(rays.size(), 7), blocked_b(rays.size(), 9);
            four.backend->intersect(rays, a);
            one->backend->intersect(rays, b);
            four.backend->occluded(rays, blocked_a);
            one->backend->occluded(rays, blocked_b);
            int differ = 0, hits = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                hits += a[i].object != KDRT_NO_HIT;
                if (std::memcmp(&a[i], &b[i], sizeof(QueryHit)) != 0 || blocked_a[i] != blocked_b[i]) {
                    ++differ;
                    UNSCOPED_INFO("ray " << i << ": four " << a[i].object << " at " << a[i].t << ", one "
                                         << b[i].object << " at " << b[i].t);
                }
            }
            CHECK(hits > static_cast<int>(rays.size()) / 4);
            CHECK(differ == 0);
            if (precision == Precision::Double) check_queries<double>(*one);
            else check_queries<float>(*one);
        }
    }
}

TEST_CASE("opencl renders: packed leaves give the one-at-a-time kernels' pictures bit for bit",
          "[opencl][render][lanes]") {
    if (!have_opencl()) return;
    // On a CPU device the renders test a small tree's leaves through packed
    // blocks of four triangles (KDRT_PACKED_LEAVES); the device described as
    // a GPU tests them one at a time from the leaf lists. The hits are the
    // same, so the id maps, the distances and the fixed-point sums are too.
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    const Scene insane = load_scene(std::string(KDRT_SCENES_DIR) + "/insane.json");
    struct Case {
        const Scene* scene;
        Traversal traversal;
        Precision precision;
    };
    const Scene queries = query_scene();
    for (const Case& c : {Case{&insane, Traversal::Stack, Precision::Float},
                          Case{&insane, Traversal::Ropes, Precision::Double},
                          Case{&queries, Traversal::Restart, Precision::Float}}) {
        if (c.precision == Precision::Double && !opencl_device().info().fp64) continue;
        INFO(to_string(c.traversal) << ", " << to_string(c.precision));
        RenderOptions o = query_options(c.traversal, c.precision);
        o.frame.width = o.frame.height = 64;
        o.frame.want_ids = true;
        const auto packed = commit_on(opencl_device(), *c.scene, o);
        const auto plain = commit_on(gpu_device, *c.scene, o);
        const RenderResult a = packed->backend->render(o.frame), b = plain->backend->render(o.frame);
        CHECK((a.stats.opencl.kernel_options.find("-DKDRT_PACKED_LEAVES") != std::string::npos) == cpu_code);
        CHECK(b.stats.opencl.kernel_options.find("-DKDRT_PACKED_LEAVES") == std::string::npos);
        CHECK(a.ids == b.ids);
        CHECK(std::memcmp(a.hit_t.data(), b.hit_t.data(), a.hit_t.size() * sizeof(float)) == 0);
        CHECK(std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)) == 0);
        CHECK(std::count_if(a.ids.begin(), a.ids.end(), [](std::int32_t id) { return id >= 0; }) > 64 * 64 / 4);
    }
}

TEST_CASE("opencl queries: the cpu device gives the same hits", "[opencl][query]") {
    if (!have_opencl()) return;
    Committed& c = committed(Traversal::Stack, Precision::Float);
    const std::vector<QueryRay> rays = adversarial_rays(c.prepared, c.kd(), 12);
    std::vector<QueryHit> gpu(rays.size()), cpu(rays.size());
    c.backend->intersect(rays, gpu);
    auto cpu_device = Device::open("cpu");
    BackendWork work;
    const auto cpu_scene = DeviceAccess::backend(cpu_device, "test").commit(c.prepared, c.kd(), c.options.commit, work);
    cpu_scene->intersect(rays, cpu);
    int differ = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        if (rays[i].t_min > 0.0f) continue;  // traced from an advanced origin on OpenCL: t rounds differently
        const bool same = gpu[i].object == cpu[i].object &&
                          (gpu[i].object == KDRT_NO_HIT || std::abs(gpu[i].t - cpu[i].t) <= 1e-5f * std::max(1.0f, cpu[i].t));
        if (!same) {
            ++differ;
            UNSCOPED_INFO("ray " << i << ": OpenCL " << gpu[i].object << " at " << gpu[i].t << ", cpu " << cpu[i].object
                                 << " at " << cpu[i].t);
        }
    }
    CHECK(differ == 0);
}

// The wide BVH's kernels (cl/traverse_bvh.cl): on a CPU device the eight
// boxes of a node as one vector and the C++ twin's sorted stack, four rays a
// work-item as a packet where they are coherent (traverse_bvh_packet.cl); described as
// a GPU, one box at a time and one stack entry per node on the path.
TEST_CASE("opencl queries: the BVH's closest and any hits agree with brute force", "[opencl][query][bvh]") {
    if (!have_opencl()) return;
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    for (DeviceBackend* device : {&opencl_device(), &gpu_device})
        for (Precision precision : {Precision::Float, Precision::Double}) {
            if (precision == Precision::Double && !opencl_device().info().fp64) continue;
            const bool gpu = device == &gpu_device;
            INFO((gpu ? "described as a GPU" : "the device as it is") << ", " << to_string(precision));
            const auto c = commit_on(*device, query_scene(), query_options(Traversal::Stack, precision, Accel::Bvh));
            const std::string kernel = c->backend->render(c->options.frame).stats.opencl.kernel_options;
            CHECK(kernel.find("-DKDRT_TRAVERSAL=5") != std::string::npos);
            CHECK((kernel.find("-DKDRT_CPU_DEVICE") != std::string::npos) == (cpu_code && !gpu));
            // A CPU device's work-items take four rays as a packet (traverse_bvh_packet.cl).
            CHECK((kernel.find("-DKDRT_PACKETS=4") != std::string::npos) == (cpu_code && !gpu));
            CHECK(kernel.find("KDRT_MAILBOX") == std::string::npos);
            if (precision == Precision::Double) check_queries<double>(*c);
            else check_queries<float>(*c);
        }
}

TEST_CASE("opencl queries: the BVH gives the cpu device's hits on the same BVH", "[opencl][query][bvh]") {
    if (!have_opencl()) return;
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    auto cpu_device = Device::open("cpu");
    for (DeviceBackend* device : {&opencl_device(), &gpu_device}) {
        INFO((device == &gpu_device ? "described as a GPU" : "the device as it is"));
        const auto c = commit_on(*device, query_scene(), query_options(Traversal::Stack, Precision::Float, Accel::Bvh));
        const std::vector<QueryRay> rays = adversarial_rays(c->prepared, c->accel(), 12);
        std::vector<QueryHit> got(rays.size()), cpu(rays.size());
        std::vector<std::uint8_t> got_any(rays.size(), 7), cpu_any(rays.size(), 7);
        c->backend->intersect(rays, got);
        c->backend->occluded(rays, got_any);
        BackendWork work;
        const auto cpu_scene =
            DeviceAccess::backend(cpu_device, "test").commit(c->prepared, c->accel(), c->options.commit, work);
        cpu_scene->intersect(rays, cpu);
        cpu_scene->occluded(rays, cpu_any);
        int differ = 0, hits = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            if (rays[i].t_min > 0.0f) continue;  // traced from an advanced origin on OpenCL: t rounds differently
            hits += cpu[i].object != KDRT_NO_HIT;
            const bool same = got[i].object == cpu[i].object && got_any[i] == cpu_any[i] &&
                              (got[i].object == KDRT_NO_HIT ||
                               std::abs(got[i].t - cpu[i].t) <= 1e-5f * std::max(1.0f, cpu[i].t));
            if (!same) {
                ++differ;
                UNSCOPED_INFO("ray " << i << ": OpenCL " << got[i].object << " at " << got[i].t << " (any "
                                     << int(got_any[i]) << "), cpu " << cpu[i].object << " at " << cpu[i].t << " (any "
                                     << int(cpu_any[i]) << ")");
            }
        }
        CHECK(differ == 0);
        CHECK(hits > static_cast<int>(rays.size()) / 4);
    }
}

TEST_CASE("opencl: the BVH's pictures on a CPU device and described as a GPU are the same bit for bit",
          "[opencl][render][bvh]") {
    if (!have_opencl()) return;
    // The CPU device's kernels test a node's eight boxes as one float8 and
    // keep every hit child on a sorted stack; the GPU's test them one by one
    // and keep a node's hit slots in one entry. Both visit the same leaves in
    // the same order, so the hits, and the fixed-point sums, are the same.
    bool cpu_code = false;
    DeviceBackend& gpu_device = described_as_gpu(cpu_code);
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"})
        for (Precision precision : {Precision::Float, Precision::Double}) {
            if (precision == Precision::Double && (std::string(name) != "lens" || !opencl_device().info().fp64)) continue;
            INFO(name << ", " << to_string(precision));
            RenderOptions o = query_options(Traversal::Stack, precision, Accel::Bvh);
            o.frame.width = 47;
            o.frame.height = 31;
            o.frame.want_ids = true;
            const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
            const auto cpu = commit_on(opencl_device(), scene, o);
            const auto gpu = commit_on(gpu_device, scene, o);
            const RenderResult a = cpu->backend->render(o.frame), b = gpu->backend->render(o.frame);
            CHECK((a.stats.opencl.kernel_options.find("-DKDRT_CPU_DEVICE") != std::string::npos) == cpu_code);
            CHECK(b.stats.opencl.kernel_options.find("KDRT_CPU_DEVICE") == std::string::npos);
            CHECK(a.ids == b.ids);
            CHECK(std::memcmp(a.hit_t.data(), b.hit_t.data(), a.hit_t.size() * sizeof(float)) == 0);
            CHECK(std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)) == 0);
            CHECK(a.stats.rays.total() == b.stats.rays.total());
            CHECK(std::count_if(a.ids.begin(), a.ids.end(), [](std::int32_t id) { return id >= 0; }) > 0);
            // The stacks the two report: the twin's sorted one, and one entry per level.
            CHECK(b.stats.opencl.traversal_stack_bytes == KDRT_BVH_SLOT_STACK_SIZE * 8u);
            if (cpu_code) CHECK(a.stats.opencl.traversal_stack_bytes > 8 * b.stats.opencl.traversal_stack_bytes);
        }
}

TEST_CASE("opencl queries: many rays in many launches", "[opencl][query]") {
    if (!have_opencl()) return;
    // 1 ms per launch: pieces of ~1024 rays; no limit: pieces as large as a
    // staging slot holds (QueryStaging::kSlotBytes; 209715 closest hits).
    // A device with memory of its own writes, traces and reads back the
    // pieces through its two staging slots in turn; one that shares the
    // host's (PoCL) traces the caller's memory in place.
    bool cpu_code = false;
    DeviceBackend& staging_device = described_as_gpu(cpu_code);
    if (cpu_code) CHECK(ocl::select_device("opencl").host_memory);  // PoCL: in place
    const bool in_place = GENERATE(true, false);
    const double launch_ms = GENERATE(1.0, 0.0);
    INFO((in_place ? "the device as it is" : "the device described as a GPU with memory of its own")
         << ", launches of at most " << launch_ms << " ms (0: no limit)");
    RenderOptions o = query_options(Traversal::Stack, Precision::Float);
    o.commit.max_query_launch_ms = launch_ms;
    const auto c = commit_on(in_place ? opencl_device() : staging_device, query_scene(), o);
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(-8.0, 8.0);
    std::vector<QueryRay> rays;
    // No limit: closest hits in four pieces, the last short; any hits (1 byte out) in three.
    const int count = launch_ms > 0.0 ? 150000 : 3 * 209715 + 1000;
    static_assert(ocl::QueryStaging::kSlotBytes / sizeof(QueryHit) == 209715);
    for (int i = 0; i < count; ++i) {
        const glm::dvec3 from = kOffset + glm::dvec3(u(rng), u(rng), u(rng)), to = kOffset + 0.5 * glm::dvec3(u(rng), u(rng), u(rng));
        rays.push_back(query_ray(from, to - from));
    }
    std::vector<QueryHit> gpu(rays.size()), cpu(rays.size());
    std::vector<std::uint8_t> any(rays.size(), 9);
    c->backend->intersect(rays, gpu);
    c->backend->occluded(rays, any);
    const Device cpu_device = Device::open("cpu");
    BackendWork work;
    const auto cpu_scene = DeviceAccess::backend(cpu_device, "test").commit(c->prepared, c->kd(), o.commit, work);
    cpu_scene->intersect(rays, cpu);
    std::size_t differ = 0, hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        hits += cpu[i].object != KDRT_NO_HIT;
        if (gpu[i].object != cpu[i].object || (cpu[i].object != KDRT_NO_HIT && gpu[i].t != cpu[i].t) ||
            any[i] != (cpu[i].object != KDRT_NO_HIT ? 1 : 0)) {
            if (++differ <= 5)
                UNSCOPED_INFO("ray " << i << ": OpenCL " << gpu[i].object << " at " << std::hexfloat << gpu[i].t << " (any "
                                     << int(any[i]) << "), cpu " << cpu[i].object << " at " << cpu[i].t << std::defaultfloat);
        }
    }
    CHECK(differ == 0);
    CHECK(hits > rays.size() / 4);
    // Spans that start off any alignment a device may want for memory it
    // wraps (one ray in; the any-hit bytes one byte in): the same answers.
    const std::span<const QueryRay> shifted = std::span<const QueryRay>(rays).subspan(1, 4099);
    std::vector<QueryHit> shifted_hits(shifted.size() + 1);
    std::vector<std::uint8_t> shifted_any(shifted.size() + 1, 9);
    c->backend->intersect(shifted, std::span<QueryHit>(shifted_hits).subspan(1));
    c->backend->occluded(shifted, std::span<std::uint8_t>(shifted_any).subspan(1));
    std::size_t shifted_differ = 0;
    for (std::size_t i = 0; i < shifted.size(); ++i)
        shifted_differ += shifted_hits[i + 1].object != gpu[i + 1].object || shifted_hits[i + 1].t != gpu[i + 1].t ||
                          shifted_any[i + 1] != any[i + 1];
    CHECK(shifted_differ == 0);
}

TEST_CASE("opencl: a second frame compiles nothing and uploads no geometry", "[opencl][query][persistent]") {
    if (!have_opencl()) return;
    RenderOptions o = query_options(Traversal::Stack, Precision::Float);
    o.frame.want_ids = true;
    auto c = commit_on(opencl_device(), query_scene(), o);
    CHECK(c->work.geometry_uploads == 1);
    CHECK(c->work.geometry_upload_bytes > 0);
    CHECK(c->work.compiles <= 1);  // 0 when an earlier test built the same variant on this device
    const RenderResult first = c->backend->render(o.frame);
    const RenderResult second = c->backend->render(o.frame);
    for (const RenderResult* r : {&first, &second}) {
        CHECK(r->stats.compiles == 0);
        CHECK(r->stats.geometry_upload_bytes == 0);
    }
    CHECK(image_rmse(first.image, second.image) == 0.0);
    CHECK(first.ids == second.ids);
    // The same picture as a commit of its own on a device of its own.
    const auto fresh_device = make_opencl_backend(ocl::select_device("opencl"));
    const auto fresh = commit_on(*fresh_device, query_scene(), o);
    const RenderResult alone = fresh->backend->render(o.frame);
    CHECK(image_rmse(alone.image, second.image) < 1e-6);
    CHECK(alone.ids == second.ids);

    // A light moved: only the shading buffers go up again, and the picture changes.
    c->prepared.lights[0].position += glm::dvec3(-6.0, -3.0, 0.0);
    BackendWork work;
    c->backend->update_shading(work);
    CHECK(work.shading_uploads == 1);
    CHECK(work.geometry_uploads == 0);
    const RenderResult moved = c->backend->render(o.frame);
    CHECK(moved.stats.compiles == 0);
    CHECK(moved.stats.geometry_upload_bytes == 0);
    CHECK(image_rmse(moved.image, second.image) > 1e-3);
    CHECK(moved.ids == second.ids);  // same geometry, same camera

    // Glass where there was none: another kernel variant, still no geometry upload.
    c->prepared.materials[0].transmit = 0.5;
    c->prepared.features.refraction = true;
    c->prepared.features.max_depth = 4;
    c->backend->update_shading(work);
    const RenderResult glass = c->backend->render(o.frame);
    CHECK(glass.stats.opencl.kernel_options.find("-DKDRT_HAS_REFRACTION") != std::string::npos);
    CHECK(glass.stats.compiles <= 1);  // 0 when an earlier test built the same variant
    CHECK(glass.stats.geometry_upload_bytes == 0);
    CHECK(image_rmse(glass.image, moved.image) > 1e-3);
}

TEST_CASE("opencl: a frame is cancelled between launches", "[opencl][query][cancel]") {
    if (!have_opencl()) return;
    Committed& c = committed(Traversal::Stack, Precision::Float);
    RenderOptions o = c.options;
    // Frame sizes are the dispatch layer's to set in the scene (backend.h).
    c.prepared.settings.width = c.prepared.settings.height = 256;  // several launches: the first takes 16384 rays
    int calls = 0;
    o.frame.progress = [&](double) { return ++calls < 2; };
    try {
        c.backend->render(o.frame);
        FAIL("the render was not cancelled");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::Cancelled);
    }
    CHECK(calls == 2);
    SECTION("the upload at commit") {
        RenderOptions commit = c.options;
        int upload_calls = 0;
        commit.commit.progress = [&](double fraction) {
            CHECK(fraction >= 0.0);
            CHECK(fraction <= 1.0);
            return ++upload_calls < 2;
        };
        try {
            commit_on(opencl_device(), query_scene(), commit);
            FAIL("the commit was not cancelled");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Cancelled);
        }
        CHECK(upload_calls == 2);
    }
    // The device and the scene are still usable, and the sums the cancelled
    // frame left do not reach the next frame's picture.
    o.frame.progress = nullptr;
    const RenderResult after = c.backend->render(o.frame), again = c.backend->render(o.frame);
    CHECK(after.image.width == 256);
    CHECK((after.image.rgb == again.image.rgb));  // not printed: 196608 floats
    c.prepared.settings.width = c.prepared.settings.height = 16;
    CHECK(c.backend->render(o.frame).image.width == 16);
    c.prepared.settings.width = c.prepared.settings.height = 48;
}

TEST_CASE("opencl: one device used from several threads at once", "[opencl][query][threads]") {
    if (!have_opencl()) return;
    Committed& a = committed(Traversal::Stack, Precision::Float);
    Committed& b = committed(Traversal::Restart, Precision::Float);
    const std::vector<QueryRay> rays = adversarial_rays(a.prepared, a.kd(), 14);
    std::vector<QueryHit> serial(rays.size());
    a.backend->intersect(rays, serial);
    RenderOptions frame = b.options;
    const RenderResult serial_frame = b.backend->render(frame.frame);
    std::vector<std::vector<QueryHit>> parallel(3, std::vector<QueryHit>(rays.size()));
    RenderResult parallel_frame;
    std::vector<std::thread> threads;
    for (int t = 0; t < 3; ++t)
        threads.emplace_back([&, t] {
            for (int k = 0; k < 3; ++k) a.backend->intersect(rays, parallel[static_cast<std::size_t>(t)]);
        });
    threads.emplace_back([&] { parallel_frame = b.backend->render(frame.frame); });
    for (std::thread& t : threads) t.join();
    for (const auto& hits : parallel) {
        int differ = 0;
        for (std::size_t i = 0; i < rays.size(); ++i)
            if (hits[i].object != serial[i].object || (hits[i].object != KDRT_NO_HIT && hits[i].t != serial[i].t)) ++differ;
        CHECK(differ == 0);
    }
    CHECK(image_rmse(parallel_frame.image, serial_frame.image) == 0.0);
}

namespace {

// The application's own OpenCL objects on the PoCL device.
struct AppCl {
    cl::Context context;
    cl::Device device;
    cl::CommandQueue queue;
    AppCl() {
        device = ocl::select_device("opencl").device;
        context = cl::Context(device);
        queue = cl::CommandQueue(context, device);
    }
};

}  // namespace

TEST_CASE("opencl queries: into the application's buffers on its own context", "[opencl][query][interop]") {
    if (!have_opencl()) return;
    AppCl app;
    const Device wrapped = wrap_opencl_device(app.context(), app.device(), app.queue());
    CHECK(wrapped.is_opencl());
    CHECK(wrapped.info().name == ocl::select_device("opencl").info.name);
    RenderOptions o = query_options(Traversal::Stack, Precision::Float);
    auto c = commit_on(DeviceAccess::backend(wrapped, "test"), query_scene(), o);
    auto* scene = dynamic_cast<OpenClSceneBackend*>(c->backend.get());
    REQUIRE(scene != nullptr);
    CHECK(scene->device_context().context()() == app.context());

    const std::vector<QueryRay> rays = adversarial_rays(c->prepared, c->kd(), 13);
    const std::size_t n = rays.size();
    std::vector<QueryHit> expected(n);
    std::vector<std::uint8_t> expected_any(n);
    committed(Traversal::Stack, Precision::Float).backend->intersect(rays, expected);
    committed(Traversal::Stack, Precision::Float).backend->occluded(rays, expected_any);

    cl::Buffer ray_buffer(app.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(QueryRay),
                          const_cast<QueryRay*>(rays.data()));
    cl::Buffer hit_buffer(app.context, CL_MEM_READ_WRITE, n * sizeof(QueryHit));
    cl::Buffer any_buffer(app.context, CL_MEM_READ_WRITE, n);

    SECTION("closest and any hit named through the commit's id table; a second round reuses the table") {
        // The name table (object, geometry, primitive of each internal id) is uploaded at the first
        // query (opencl_backend.h): before it, application ids unlike the internal ones, in
        // geometries of seven objects, so that no column of the table is the identity.
        const std::size_t objects = c->prepared.geometry_f.object_count();
        c->prepared.public_ids.resize(objects);
        c->prepared.geometry_first.clear();
        for (std::size_t i = 0; i < objects; ++i) {
            c->prepared.public_ids[i] = static_cast<std::uint32_t>(1000 + 3 * i);
            if (i % 7 == 0) c->prepared.geometry_first.push_back(c->prepared.public_ids[i]);
        }
        const std::vector<std::uint32_t> names = c->prepared.name_table();
        REQUIRE(names.size() == 3 * objects);
        REQUIRE(names[3 * 9] == 1027);
        REQUIRE(names[3 * 9 + 1] == 1);  // object 9: geometry 1 (first id 1021), primitive 6
        REQUIRE(names[3 * 9 + 2] == 6);
        for (int round = 0; round < 2; ++round) {
            scene->intersect(ray_buffer(), hit_buffer(), n);
            scene->occluded(ray_buffer(), any_buffer(), n);
            std::vector<QueryHit> hits(n);
            std::vector<std::uint8_t> any(n);
            app.queue.enqueueReadBuffer(hit_buffer, CL_TRUE, 0, n * sizeof(QueryHit), hits.data());
            app.queue.enqueueReadBuffer(any_buffer, CL_TRUE, 0, n, any.data());
            int differ = 0;
            for (std::size_t i = 0; i < n; ++i) {
                const std::uint32_t id = expected[i].object;
                const bool hit = id != KDRT_NO_HIT;
                if (hits[i].object != (hit ? names[3 * id] : KDRT_NO_HIT) || (hit && hits[i].t != expected[i].t) ||
                    any[i] != expected_any[i])
                    ++differ;
                if (hit && (hits[i].geometry != names[3 * id + 1] || hits[i].primitive != names[3 * id + 2])) ++differ;
            }
            CHECK(differ == 0);
            // Changed after the upload, the ids must not reach the second round: the table is the commit's.
            for (std::uint32_t& id : c->prepared.public_ids) id += 1;
        }
    }
    auto expect_error = [&](auto&& call, const std::string& words) {
        try {
            call();
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK_THAT(std::string(e.what()), Catch::Contains(words));
        }
    };
    SECTION("a buffer too small") {
        expect_error([&] { scene->intersect(ray_buffer(), hit_buffer(), n + 1); }, "the rays buffer holds");
        cl::Buffer small(app.context, CL_MEM_READ_WRITE, n * sizeof(QueryHit) - 1);
        expect_error([&] { scene->intersect(ray_buffer(), small(), n); }, "the hits buffer holds");
        cl::Buffer tiny(app.context, CL_MEM_READ_WRITE, n - 1);
        expect_error([&] { scene->occluded(ray_buffer(), tiny(), n); }, "the occluded buffer holds");
    }
    SECTION("buffers of another context, read-only results, null") {
        cl::Context other(app.device);
        cl::Buffer foreign(other, CL_MEM_READ_WRITE, n * sizeof(QueryHit));
        expect_error([&] { scene->intersect(foreign(), hit_buffer(), n); }, "another OpenCL context");
        expect_error([&] { scene->intersect(ray_buffer(), foreign(), n); }, "another OpenCL context");
        cl::Buffer read_only(app.context, CL_MEM_READ_ONLY, n * sizeof(QueryHit));
        expect_error([&] { scene->intersect(ray_buffer(), read_only(), n); }, "CL_MEM_READ_ONLY");
        expect_error([&] { scene->occluded(nullptr, any_buffer(), n); }, "null");
    }
}

TEST_CASE("opencl: wrapping the application's objects checks them", "[opencl][query][interop]") {
    if (!have_opencl()) return;
    AppCl app;
    cl::Context other(app.device);
    cl::CommandQueue other_queue(other, app.device);
    auto expect_device_error = [&](auto&& call, const std::string& words) {
        try {
            call();
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Device);
            CHECK_THAT(std::string(e.what()), Catch::Contains(words));
        }
    };
    expect_device_error([&] { wrap_opencl_device(app.context(), app.device(), other_queue()); }, "another cl_context");
    expect_device_error([&] { wrap_opencl_device(nullptr, app.device(), app.queue()); }, "null cl_context");
    expect_device_error([&] { wrap_opencl_device(app.context(), app.device(), nullptr); }, "null cl_command_queue");
    // The wrapped objects are retained: the device outlives the application's handles.
    std::optional<Device> wrapped;
    {
        AppCl scoped;
        wrapped = wrap_opencl_device(scoped.context(), scoped.device(), scoped.queue());
    }
    auto c = commit_on(DeviceAccess::backend(*wrapped, "test"), query_scene(), query_options(Traversal::Stack, Precision::Float));
    c->prepared.settings.width = c->prepared.settings.height = 8;
    CHECK(c->backend->render(c->options.frame).image.width == 8);
}

TEST_CASE("opencl queries: kdrt::intersect on cl_mem gives the host spans' hits and ids", "[opencl][query][interop]") {
    if (!have_opencl()) return;
    AppCl app;
    const Device device = wrap_opencl_device(app.context(), app.device(), app.queue());
    // Triangles added before spheres: the public ids are not the internal ones (spheres first).
    Scene s;
    auto m = s.add_material({});
    std::vector<glm::dvec3> centres;
    for (int i = 0; i < 6; ++i) {
        const glm::dvec3 c = kOffset + glm::dvec3(2.0 * i - 5.0, 0.0, 0.0);
        if (i % 2 == 0) s.add_triangle(c + glm::dvec3(-0.8, -0.8, 0), c + glm::dvec3(0.8, -0.8, 0), c + glm::dvec3(0, 0.8, 0), m);
        else s.add_sphere(c, 0.7, m);
        centres.push_back(c);
    }
    s.camera.position = kOffset + glm::dvec3(0, 0, -10);
    s.camera.look_at = kOffset;
    RenderOptions o = query_options(Traversal::Stack, Precision::Float);
    CommittedScene scene = CommittedScene::commit(device, s, o.commit);
    REQUIRE_FALSE(CommittedSceneAccess::state(scene, "test").prepared.public_ids.empty());
    CHECK(scene.stats().geometry_uploads == 1);

    std::vector<QueryRay> rays;
    for (const glm::dvec3& c : centres) {
        rays.push_back(query_ray(c + glm::dvec3(0.1, 0.1, -5.0), glm::dvec3(0, 0, 2.0)));
        rays.push_back(query_ray(c + glm::dvec3(0.1, 0.1, -5.0), glm::dvec3(0, 0, 2.0), 0.0f, 1.0f));  // stops short
    }
    const std::size_t n = rays.size();
    std::vector<QueryHit> expected(n);
    std::vector<std::uint8_t> expected_any(n);
    intersect(scene, rays, expected);
    occluded(scene, rays, expected_any);
    for (std::size_t i = 0; i < centres.size(); ++i) {
        CHECK(expected[2 * i].object == i);  // the id add_* returned
        CHECK(expected[2 * i + 1].object == KDRT_NO_HIT);
        CHECK(expected_any[2 * i] == 1);
        CHECK(expected_any[2 * i + 1] == 0);
    }
    cl::Buffer ray_buffer(app.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(QueryRay),
                          const_cast<QueryRay*>(rays.data()));
    cl::Buffer hit_buffer(app.context, CL_MEM_WRITE_ONLY, n * sizeof(QueryHit));
    cl::Buffer any_buffer(app.context, CL_MEM_WRITE_ONLY, n);
    intersect(scene, ray_buffer(), hit_buffer(), n);
    occluded(scene, ray_buffer(), any_buffer(), n);
    std::vector<QueryHit> hits(n);
    std::vector<std::uint8_t> any(n);
    app.queue.enqueueReadBuffer(hit_buffer, CL_TRUE, 0, n * sizeof(QueryHit), hits.data());
    app.queue.enqueueReadBuffer(any_buffer, CL_TRUE, 0, n, any.data());
    for (std::size_t i = 0; i < n; ++i) {
        CHECK(hits[i].object == expected[i].object);
        if (hits[i].object != KDRT_NO_HIT) CHECK(hits[i].t == expected[i].t);
        CHECK(any[i] == expected_any[i]);
    }
    // Frames and queries upload no geometry again.
    const RenderResult first = scene.render(o.frame), second = scene.render(o.frame);
    CHECK(second.stats.compiles == 0);
    CHECK(second.stats.geometry_upload_bytes == 0);
    CHECK(scene.stats().geometry_uploads == 1);
    CHECK(image_rmse(first.image, second.image) == 0.0);

    SECTION("after an update with the objects added in another order, the hits carry the new ids") {
        Scene reordered;
        reordered.add_material({});
        for (int odd = 1; odd >= 0; --odd)  // spheres first this time
            for (std::size_t i = odd; i < centres.size(); i += 2) {
                const glm::dvec3 c = centres[i];
                if (i % 2 == 0)
                    reordered.add_triangle(c + glm::dvec3(-0.8, -0.8, 0), c + glm::dvec3(0.8, -0.8, 0),
                                           c + glm::dvec3(0, 0.8, 0), m);
                else reordered.add_sphere(c, 0.7, m);
            }
        reordered.camera = s.camera;
        scene.update(reordered);
        std::vector<QueryHit> now(n);
        intersect(scene, rays, now);
        CHECK(now[0].object != expected[0].object);
        intersect(scene, ray_buffer(), hit_buffer(), n);
        app.queue.enqueueReadBuffer(hit_buffer, CL_TRUE, 0, n * sizeof(QueryHit), hits.data());
        for (std::size_t i = 0; i < n; ++i) {
            CHECK(hits[i].object == now[i].object);
            CHECK(hits[i].geometry == now[i].geometry);
        }
    }
    SECTION("a scene on the cpu device has no cl_mem queries") {
        const CommittedScene on_cpu = CommittedScene::commit(Device::open("cpu"), s, o.commit);
        try {
            intersect(on_cpu, ray_buffer(), hit_buffer(), n);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK_THAT(std::string(e.what()), Catch::Contains("not on an OpenCL device"));
        }
    }
}

