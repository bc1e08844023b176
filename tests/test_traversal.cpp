// Every kd-tree traversal, on trees from every builder, returns exactly the
// closest hit (id and t) that brute force returns: on random rays and on
// adversarial ones (axis-parallel with +0 and -0 components, lying in split
// planes, starting on split planes and on objects, inside and outside the box).
#include "bvh/bvh_build.h"
#include "cpu/tracer.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <array>
#include <initializer_list>
#include <random>
#include <utility>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

// Spheres and triangles with the hard cases: degenerate triangles (zero area,
// collinear, repeated vertices), axis-aligned and coplanar triangles, and a
// grid of quads whose edges all lie on the same few planes.
Scene hard_random_scene(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0), small(0.05, 0.6);
    std::uniform_int_distribution<int> grid(-4, 4);
    Scene s;
    auto m = s.add_material({});
    for (int i = 0; i < 25; ++i) s.add_sphere({u(rng), u(rng), u(rng)}, small(rng), m);
    // Spheres on integer planes, touching each other.
    for (int i = 0; i < 6; ++i) s.add_sphere({grid(rng), grid(rng), grid(rng)}, 0.5, m);
    for (int i = 0; i < 60; ++i) {
        glm::dvec3 a{u(rng), u(rng), u(rng)};
        s.add_triangle(a, a + glm::dvec3(small(rng), small(rng), u(rng) * 0.2),
                       a + glm::dvec3(-small(rng), small(rng), small(rng)), m);
    }
    // Axis-aligned, coplanar unit quads on a grid: their edges share split planes.
    for (int x = -3; x < 3; ++x)
        for (int y = -3; y < 3; ++y) {
            glm::dvec3 p{x, y, 1.0};
            s.add_triangle(p, p + glm::dvec3(1, 0, 0), p + glm::dvec3(1, 1, 0), m);
            s.add_triangle(p, p + glm::dvec3(1, 1, 0), p + glm::dvec3(0, 1, 0), m);
        }
    // Walls in the other two axes through the same integer planes.
    for (int i = -2; i < 2; ++i) {
        s.add_triangle({0, i, -2}, {0, i + 1, -2}, {0, i + 1, 2}, m);
        s.add_triangle({i, 2, -2}, {i + 1, 2, 2}, {i, 2, 2}, m);
    }
    // Degenerate triangles: zero area, collinear, repeated vertices.
    s.add_triangle({1, 1, 1}, {1, 1, 1}, {1, 1, 1}, m);
    s.add_triangle({0, 0, 0}, {1, 1, 1}, {2, 2, 2}, m);
    s.add_triangle({-1, 0, 0}, {-1, 0, 0}, {-1, 1, 0}, m);
    return s;
}

// Random and adversarial rays for a prepared scene and its tree.
template <class Real>
std::vector<Ray<Real>> adversarial_rays(const PreparedScene& p, const KdTree& tree, std::uint32_t seed) {
    using Vec = glm::vec<3, Real>;
    std::mt19937 rng(seed);
    const Aabb& b = p.bounds;
    const glm::dvec3 lo = b.lo - 0.5 * b.extent(), hi = b.hi + 0.5 * b.extent();
    auto rnd = [&](double a, double c) { return std::uniform_real_distribution<double>(a, c)(rng); };
    auto point = [&](bool inside) {
        const glm::dvec3 l = inside ? b.lo : lo, h = inside ? b.hi : hi;
        return Vec(Real(rnd(l.x, h.x)), Real(rnd(l.y, h.y)), Real(rnd(l.z, h.z)));
    };
    auto dir = [&]() {
        Vec d;
        do d = Vec(Real(rnd(-1, 1)), Real(rnd(-1, 1)), Real(rnd(-1, 1)));
        while (glm::length(d) < Real(0.1));
        return glm::normalize(d);
    };
    std::vector<Ray<Real>> rays;
    // Random rays from inside and outside the box, towards random points.
    for (int i = 0; i < 400; ++i) {
        Vec o = point(i % 2 == 0);
        Vec target = point(true);
        if (glm::length(target - o) > Real(0)) rays.emplace_back(o, glm::normalize(target - o));
        rays.emplace_back(o, dir());
    }
    // Axis-parallel rays, with +0 and -0 in the other components.
    const Real zeros[2] = {Real(0), -Real(0)};
    for (int i = 0; i < 300; ++i) {
        Vec o = point(i % 3 != 0);
        int axis = i % 3;
        Vec d(zeros[i & 1], zeros[(i >> 1) & 1], zeros[(i >> 2) & 1]);
        d[axis] = (i & 8) ? Real(1) : Real(-1);
        rays.emplace_back(o, d);
    }
    // Rays lying exactly in split planes, and rays starting exactly on them.
    std::vector<std::pair<int, float>> planes;
    for (const KdNode& n : tree.nodes)
        if (!kd_is_leaf(n)) planes.emplace_back(kd_axis(n), kd_split(n));
    std::shuffle(planes.begin(), planes.end(), rng);
    if (planes.size() > 200) planes.resize(200);
    for (auto [axis, split] : planes) {
        Vec o = point(true);
        o[axis] = Real(split);
        Vec d = dir();
        d[axis] = zeros[rng() & 1];
        if (glm::length(d) == Real(0)) continue;
        rays.emplace_back(o, glm::normalize(d));  // in the plane
        Vec d2 = dir();
        rays.emplace_back(o, d2);  // starting on the plane
        // Axis-parallel and in the plane at once.
        Vec d3(0);
        d3[(axis + 1) % 3] = (rng() & 1) ? Real(1) : Real(-1);
        rays.emplace_back(o, d3);
    }
    // Rays starting exactly on objects: triangle vertices and sphere poles.
    const auto& g = p.geometry<Real>();
    for (std::size_t i = 0; i < g.triangles.size(); i += 3) rays.emplace_back(g.triangles[i].v1, dir());
    for (const auto& s : g.spheres) rays.emplace_back(s.center + Vec(0, s.radius, 0), dir());
    // Rays aimed exactly at triangle vertices (shared between grid quads).
    for (std::size_t i = 0; i < g.triangles.size(); i += 2) {
        Vec o = point(false);
        Vec d = g.triangles[i].v0 - o;
        if (glm::length(d) > Real(0)) rays.emplace_back(o, glm::normalize(d));
    }
    return rays;
}

// Long triangles crossing the whole box (each in very many leaves) among
// small ones: the mailbox's collisions and evictions on every ray.
Scene duplicated_objects_scene(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0), small(0.05, 0.5);
    Scene s;
    auto m = s.add_material({});
    for (int i = 0; i < 8; ++i) s.add_sphere({u(rng), u(rng), u(rng)}, 1.5, m);  // spheres over many leaves
    for (int i = 0; i < 48; ++i) {
        const glm::dvec3 a{u(rng), u(rng), u(rng)};
        s.add_triangle(a, -a + glm::dvec3(small(rng), 0, 0), glm::dvec3(u(rng), u(rng), u(rng)), m);
        for (int k = 0; k < 4; ++k) {
            const glm::dvec3 b{u(rng), u(rng), u(rng)};
            s.add_triangle(b, b + glm::dvec3(small(rng), small(rng), 0), b + glm::dvec3(0, small(rng), small(rng)), m);
        }
    }
    return s;
}

// The oracle: every object through intersect_object, one at a time. The
// tracers' own brute force (Traversal::None) takes a leaf's triangles four at
// a time (test_leaf_ray), so it is checked against this like the trees are.
template <class Real>
struct ObjectByObject {
    const SceneGeometry<Real>& g;
    Hit<Real> closest(const Ray<Real>& ray) const {
        Hit<Real> best;
        for (std::uint32_t id = 0; id < g.object_count(); ++id) intersect_object(g, ray, id, best);
        return best;
    }
    bool occluded(const Ray<Real>& ray, Real t_max) const {
        for (std::uint32_t id = 0; id < g.object_count(); ++id) {
            Hit<Real> h;
            intersect_object(g, ray, id, h);
            if (h.valid() && h.t < t_max) return true;
        }
        return false;
    }
};

// Packets of N rays for the packet traversal: the adversarial rays in
// consecutive groups (mostly mixed signs: the single-ray fallback), and around
// each of them a camera-like fan (one origin, jittered directions) and a
// parallel beam (one direction, origins moved within the axis planes through
// the ray's origin, so rays starting on a split plane all start on it).
template <class Real, int N>
std::vector<std::array<Ray<Real>, N>> packets_of(const std::vector<Ray<Real>>& rays, std::uint32_t seed) {
    using Vec = glm::vec<3, Real>;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jitter(-0.05, 0.05);
    std::vector<std::array<Ray<Real>, N>> packets;
    auto make = [&](auto&& lane) {
        packets.push_back([&]<std::size_t... I>(std::index_sequence<I...>) {
            return std::array<Ray<Real>, N>{lane(int(I))...};
        }(std::make_index_sequence<N>{}));
    };
    for (std::size_t i = 0; i + N <= rays.size(); i += N) make([&](int k) { return rays[i + std::size_t(k)]; });
    for (const Ray<Real>& r : rays) {
        std::vector<Vec> dirs;
        for (int k = 0; k < N; ++k) {
            Vec d = r.dir + Vec(Real(jitter(rng)), Real(jitter(rng)), Real(jitter(rng)));
            dirs.push_back(glm::length(d) > Real(0) ? glm::normalize(d) : r.dir);
        }
        make([&](int k) { return Ray<Real>(r.org, k == 0 ? r.dir : dirs[std::size_t(k)]); });
        const int axis = int(rng() % 3);
        make([&](int k) {
            Vec o = r.org;
            o[(axis + 1) % 3] += Real(0.01 * k);
            o[(axis + 2) % 3] -= Real(0.013 * k);
            return Ray<Real>(o, r.dir);
        });
    }
    return packets;
}

// The packet queries of each tracer give its single-ray traversal's results
// bit for bit (id, t, barycentrics), and so brute force's: closest hits, and
// shadow queries with per-lane limits before, at and beyond each lane's hit.
// Brute force answers each lane once for all the tracers.
template <class Real, int N>
void check_packets(const ObjectByObject<Real>& brute, std::initializer_list<const Tracer<Real>*> tracers,
                   const std::vector<Ray<Real>>& rays, std::uint32_t seed) {
    std::vector<std::size_t> packed(tracers.size(), 0);
    std::size_t mismatches = 0, blocked_mismatches = 0, hits = 0;
    const auto packets = packets_of<Real, N>(rays, seed);
    for (const auto& packet : packets) {
        const Ray<Real>* lanes[N];
        Hit<Real> truth[N];
        Real limits[3][N];
        bool truly_blocked[3][N];
        const Real fs[3] = {Real(0.999), Real(1), Real(1.5)};
        for (int k = 0; k < N; ++k) {
            lanes[k] = &packet[std::size_t(k)];
            truth[k] = brute.closest(*lanes[k]);
            hits += truth[k].valid();
            for (int f = 0; f < 3; ++f) {
                limits[f][k] = truth[k].valid() ? truth[k].t * fs[f] : Real(100);
                truly_blocked[f][k] = brute.occluded(*lanes[k], limits[f][k]);
            }
        }
        std::size_t t = 0;
        for (const Tracer<Real>* tracer : tracers) {
            packed[t++] += tracer->packs(lanes);
            Hit<Real> got[N];
            tracer->closest(lanes, got);
            for (int k = 0; k < N; ++k) {
                const Hit<Real> alone = tracer->closest(*lanes[k]);
                const bool same = got[k].id == alone.id && got[k].t == alone.t && got[k].b1 == alone.b1 &&
                                  got[k].b2 == alone.b2 && got[k].id == truth[k].id && got[k].t == truth[k].t;
                if (!same && mismatches < 5)
                    UNSCOPED_INFO("tracer " << t - 1 << ", lane " << k << " o=(" << lanes[k]->org.x << ","
                                            << lanes[k]->org.y << "," << lanes[k]->org.z << ") d=(" << lanes[k]->dir.x
                                            << "," << lanes[k]->dir.y << "," << lanes[k]->dir.z << "): packet "
                                            << got[k].id << "@" << got[k].t << ", alone " << alone.id << "@"
                                            << alone.t << ", brute " << truth[k].id << "@" << truth[k].t);
                mismatches += !same;
            }
            for (int f = 0; f < 3; ++f) {
                bool blocked[N];
                tracer->occluded(lanes, limits[f], blocked);
                for (int k = 0; k < N; ++k)
                    blocked_mismatches += blocked[k] != tracer->occluded(*lanes[k], limits[f][k]) ||
                                          blocked[k] != truly_blocked[f][k];
            }
        }
    }
    for (std::size_t t = 0; t < tracers.size(); ++t) {
        INFO(N << " lanes, tracer " << t << ": " << packets.size() << " packets, " << packed[t]
               << " traced as packets");
        CHECK(packed[t] > packets.size() / 4);  // the packet path is really taken
    }
    INFO(N << " lanes: " << packets.size() << " packets, " << hits << " hits");
    CHECK(hits > packets.size() * N / 4);
    CHECK(mismatches == 0);
    CHECK(blocked_mismatches == 0);
}

template <class Real>
void check_all_traversals(const Scene& scene, std::uint32_t seed) {
    CommitOptions o;
    o.accuracy.precision = sizeof(Real) == sizeof(double) ? Precision::Double : Precision::Float;
    const PreparedScene p = prepare_scene(scene, o);
    const auto& g = p.geometry<Real>();
    const ObjectByObject<Real> brute{g};
    const Tracer<Real> none(g, nullptr, Traversal::None);
    for (KdBuilderKind builder : {KdBuilderKind::Median, KdBuilderKind::Sah}) {
        KdBuildConfig config;
        config.builder = builder;
        KdTree tree = build_kd_tree(p.build_input(), config);
        build_ropes(tree);
        check_kd_tree(tree);
        const auto rays = adversarial_rays<Real>(p, tree, seed);
        // The short stack also with 1 and 2 entries: nearly every ray restarts, often from pushed-down nodes.
        const Tracer<Real, 1> short1(g, &tree, Traversal::ShortStack);
        const Tracer<Real, 2> short2(g, &tree, Traversal::ShortStack);
        const Tracer<Real> restart(g, &tree, Traversal::Restart), ropes(g, &tree, Traversal::Ropes),
            stack(g, &tree, Traversal::Stack), short_default(g, &tree, Traversal::ShortStack);
        // The leaves as the tree stores them, as big trees are traced (packed_leaves.h).
        const Tracer<Real> stack_unpacked(g, &tree, Traversal::Stack, {}, false);
        CHECK(stack.leaves_packed());
        CHECK_FALSE(stack_unpacked.leaves_packed());
        // Brute force's answers, once for every tracer: the closest hit, and
        // shadow queries just before, just after and well beyond it.
        constexpr Real kShadowFactors[3] = {Real(0.999), Real(1.001), Real(1.5)};
        std::vector<Hit<Real>> truth(rays.size());
        std::vector<std::array<bool, 3>> truly_blocked(rays.size());
        for (std::size_t i = 0; i < rays.size(); ++i) {
            truth[i] = brute.closest(rays[i]);
            for (int f = 0; f < 3; ++f)
                truly_blocked[i][f] =
                    brute.occluded(rays[i], truth[i].valid() ? truth[i].t * kShadowFactors[f] : Real(100));
        }
        auto check_tracer = [&](const auto& fast, const std::string& name) {
            std::size_t mismatches = 0, blocked_mismatches = 0, hits = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                const Ray<Real>& ray = rays[i];
                const Hit<Real>& a = truth[i];
                const Hit<Real> b = fast.closest(ray);
                hits += a.valid();
                if (a.id != b.id || a.t != b.t || a.b1 != b.b1 || a.b2 != b.b2) {
                    if (mismatches < 5)
                        UNSCOPED_INFO("ray o=(" << ray.org.x << "," << ray.org.y << "," << ray.org.z << ") d=("
                                                << ray.dir.x << "," << ray.dir.y << "," << ray.dir.z << "): brute "
                                                << a.id << "@" << a.t << ", tree " << b.id << "@" << b.t);
                    ++mismatches;
                }
                for (int f = 0; f < 3; ++f) {
                    const Real tmax = a.valid() ? a.t * kShadowFactors[f] : Real(100);
                    const bool blocked = fast.occluded(ray, tmax);
                    blocked_mismatches += truly_blocked[i][f] != blocked;
                    // Nothing nearer than the closest hit may block.
                    if (a.valid() && kShadowFactors[f] < Real(1)) blocked_mismatches += blocked;
                }
            }
            INFO("builder " << to_string(builder) << ", traversal " << name << ", " << rays.size() << " rays, "
                            << hits << " hits");
            CHECK(hits > rays.size() / 4);
            CHECK(mismatches == 0);
            CHECK(blocked_mismatches == 0);
        };
        check_tracer(none, "none");
        check_tracer(restart, "restart");
        check_tracer(ropes, "ropes");
        check_tracer(stack, "stack");
        check_tracer(stack_unpacked, "stack (leaves unpacked)");
        check_tracer(short_default, "short-stack");
        check_tracer(short1, "short-stack (1 entry)");
        check_tracer(short2, "short-stack (2 entries)");
        if (builder == KdBuilderKind::Sah) {  // the BVH's tracer once (it does not depend on the kd builder)
            const auto spheres = static_cast<std::uint32_t>(g.spheres.size());
            const WideBvh bvh = build_wide_bvh(BvhBuildInput{p.object_bounds(), spheres});
            const Tracer<Real> wide(g, AccelRef(nullptr, &bvh), Traversal::Stack);
            REQUIRE(wide.leaves_packed());
            check_tracer(wide, "BVH");
            check_packets<Real, 4>(brute, {&stack, &wide}, rays, seed);
            check_packets<Real, 8>(brute, {&stack, &wide}, rays, seed + 1);
        } else {
            check_packets<Real, 4>(brute, {&stack}, rays, seed);
            check_packets<Real, 8>(brute, {&stack}, rays, seed + 1);
        }
    }
}

}  // namespace

TEST_CASE("traversal: every traversal equals brute force on hard random scenes", "[traversal][slow]") {
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        INFO("seed " << seed);
        const Scene s = hard_random_scene(seed);
        check_all_traversals<float>(s, seed);
        check_all_traversals<double>(s, seed + 100);
    }
}

TEST_CASE("traversal: objects in many leaves (mailboxing) still give brute force's hits", "[traversal][slow]") {
    for (std::uint32_t seed : {7u, 8u}) {
        INFO("seed " << seed);
        const Scene s = duplicated_objects_scene(seed);
        check_all_traversals<float>(s, seed);
        check_all_traversals<double>(s, seed + 100);
    }
}

TEST_CASE("traversal: the mailbox remembers tested ids and forgets on collision only", "[traversal]") {
    Mailbox box;
    CHECK_FALSE(box.seen(5));
    CHECK(box.seen(5));
    CHECK_FALSE(box.seen(6));
    CHECK(box.seen(5));
    // Same slot: the newer id evicts the older, which is then tested again (never skipped wrongly).
    CHECK_FALSE(box.seen(5 + KDRT_MAILBOX_SIZE));
    CHECK_FALSE(box.seen(5));
    CHECK(box.seen(5));
    // The empty marker is no object id, and id 0 is not taken for seen at the start.
    Mailbox fresh;
    CHECK_FALSE(fresh.seen(0));
}

// The acceptance test of the kd-tree issue at reduced size: camera-ray id maps
// of the five scenes are identical for every builder and traversal.
TEST_CASE("traversal: id maps of the five scenes match brute force", "[traversal][scenes]") {
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"}) {
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        CommitOptions o;
        const PreparedScene p = prepare_scene(scene, o);
        const int W = 64, H = 64;
        const CameraFrame cam(p.camera, W, H);
        std::vector<Ray<float>> rays;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) rays.emplace_back(glm::vec3(cam.position), glm::vec3(cam.direction(x, y, W, H)));
        const Tracer<float> brute(p.geometry_f, nullptr, Traversal::None);
        std::vector<Hit<float>> expected;
        for (const auto& r : rays) expected.push_back(brute.closest(r));
        for (KdBuilderKind builder : {KdBuilderKind::Median, KdBuilderKind::Sah}) {
            KdBuildConfig config;
            config.builder = builder;
            KdTree tree = build_kd_tree(p.build_input(), config);
            build_ropes(tree);
            auto check_tracer = [&](const auto& fast, const std::string& traversal) {
                std::size_t differ = 0;
                for (std::size_t i = 0; i < rays.size(); ++i) {
                    const Hit<float> h = fast.closest(rays[i]);
                    differ += h.id != expected[i].id || h.t != expected[i].t;
                }
                INFO(name << ": builder " << to_string(builder) << ", traversal " << traversal);
                CHECK(differ == 0);
            };
            for (Traversal t : {Traversal::Restart, Traversal::Ropes, Traversal::Stack, Traversal::ShortStack})
                check_tracer(Tracer<float>(p.geometry_f, &tree, t), to_string(t));
            check_tracer(Tracer<float, 1>(p.geometry_f, &tree, Traversal::ShortStack), "short-stack (1 entry)");
        }
    }
}

// The short stack's restarts (Horn et al. 2007) must neither skip nor repeat a
// leaf: with 1, 2 and the default number of entries it meets exactly the leaves
// the full stack meets, in the same order, when no hit ends the ray early.
TEST_CASE("traversal: the short stack visits the full stack's leaves in order", "[traversal]") {
    const Scene s = hard_random_scene(5);
    CommitOptions o;
    const PreparedScene p = prepare_scene(s, o);
    KdBuildConfig config;
    config.max_depth = 20;
    const KdTree tree = build_kd_tree(p.build_input(), config);
    using Leaf = std::pair<const std::uint32_t*, std::uint32_t>;
    auto recorder = [](std::vector<Leaf>& out) {
        return [&out](const std::uint32_t* ids, std::uint32_t count) {
            out.emplace_back(ids, count);
            return std::numeric_limits<float>::infinity();
        };
    };
    std::size_t long_rays = 0;
    const auto rays = adversarial_rays<float>(p, tree, 5);
    for (const Ray<float>& ray : rays) {
        std::vector<Leaf> full, one, two, dflt;
        const float inf = std::numeric_limits<float>::infinity();
        traverse_stack(tree, ray, inf, recorder(full));
        traverse_short_stack<1>(tree, ray, inf, recorder(one));
        traverse_short_stack<2>(tree, ray, inf, recorder(two));
        traverse_short_stack(tree, ray, inf, recorder(dflt));
        long_rays += full.size() >= 8;  // more far children pending than 1 or 2 entries can hold
        REQUIRE(one == full);
        REQUIRE(two == full);
        REQUIRE(dflt == full);
    }
    INFO(long_rays << " of " << rays.size() << " rays cross 8 or more leaves");
    CHECK(long_rays > rays.size() / 10);
}
