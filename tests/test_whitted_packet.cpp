// The cpu renderer shades camera packets with WhittedTracer::shade_packet,
// which traces the lanes' shadow, mirror and refracted rays as packets. Each
// lane's colour and the ray counts must be exactly what shade() gives the
// lane's ray alone, on scenes with mirrors and glass, spheres and triangles,
// in both precisions, for full and partial packets.
#include "bvh/bvh_build.h"
#include "cpu/tracer.h"
#include "cpu/whitted_tracer.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <random>
#include <string>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

// Mirror and glass on flat and curved objects: a mirror floor, a glass pane, a
// mirror and a glass sphere, and matte triangles and spheres strewn around.
Scene mirrors_and_glass_scene(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-3.0, 3.0), small(0.2, 0.8);
    Scene s;
    Material mirror;
    mirror.reflect = 0.8;
    mirror.specular = 0.5;
    Material glass;
    glass.transmit = 0.9;
    glass.reflect = 0.1;
    glass.ior = 1.5;
    Material matte;
    matte.color = {0.7, 0.4, 0.2};
    const auto m_mirror = s.add_material(mirror), m_glass = s.add_material(glass), m_matte = s.add_material(matte);
    s.add_triangle({-6, -1, -6}, {6, -1, -6}, {6, -1, 6}, m_mirror);
    s.add_triangle({-6, -1, -6}, {6, -1, 6}, {-6, -1, 6}, m_mirror);
    s.add_triangle({-2, -1, 1}, {2, -1, 1}, {2, 2, 1}, m_glass);
    s.add_triangle({-2, -1, 1}, {2, 2, 1}, {-2, 2, 1}, m_glass);
    s.add_sphere({-1.5, 0.2, 2.5}, 0.9, m_mirror);
    s.add_sphere({1.5, 0.2, -0.5}, 0.8, m_glass);
    for (int i = 0; i < 20; ++i) {
        const glm::dvec3 a{u(rng), u(rng) * 0.5 + 0.5, u(rng) + 3.0};
        s.add_triangle(a, a + glm::dvec3(small(rng), 0.1, 0.0), a + glm::dvec3(0.0, small(rng), 0.2), m_matte);
        s.add_sphere({u(rng), u(rng) * 0.5, u(rng) + 4.0}, small(rng) * 0.5, i % 3 ? m_matte : m_mirror);
    }
    s.add_light({{3.0, 5.0, -4.0}, {0.8, 0.8, 0.8}});
    s.add_light({{-4.0, 3.0, -2.0}, {0.4, 0.4, 0.5}});
    s.camera.position = {0.0, 1.5, -7.0};
    s.camera.look_at = {0.0, 0.0, 1.0};
    return s;
}

// packets_expected: most camera packets must take the packet traversal.
template <class Real>
void check_shade_packet(const PreparedScene& p, const Tracer<Real>& tracer, const std::string& name,
                        bool packets_expected) {
    using Vec = glm::vec<3, Real>;
    const WhittedTracer<Real, Tracer<Real>> whitted(p, tracer);
    const int W = 48, H = 48;
    const CameraFrame cam(p.camera, W, H);
    const std::uint32_t masks[] = {0xFu, 0x7u, 0x5u, 0x8u};
    std::size_t packets = 0, packed = 0, differ = 0, count_differ = 0;
    RayCounts total;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x + 4 <= W; x += 4) {
            const Ray<Real> rays[4] = {
                Ray<Real>(Vec(cam.position), Vec(cam.direction(x, y, W, H))),
                Ray<Real>(Vec(cam.position), Vec(cam.direction(x + 1, y, W, H))),
                Ray<Real>(Vec(cam.position), Vec(cam.direction(x + 2, y, W, H))),
                Ray<Real>(Vec(cam.position), Vec(cam.direction(x + 3, y, W, H)))};
            const Ray<Real>* lanes[4] = {&rays[0], &rays[1], &rays[2], &rays[3]};
            Hit<Real> hits[4];
            tracer.closest(lanes, hits);
            packed += tracer.packs(lanes);
            const std::uint32_t used = masks[static_cast<std::size_t>(x / 4 + y) % 4];
            RayCounts got, want;
            Vec color[4];
            whitted.shade_packet(lanes, hits, used, 1, got, color);
            for (int k = 0; k < 4; ++k) {
                if (!(used >> k & 1u)) continue;
                const Vec alone = whitted.shade(rays[k], hits[k], 1, want);
                if (color[k] != alone && differ < 5)
                    UNSCOPED_INFO("pixel " << x + k << "," << y << ": packet " << color[k].x << " " << color[k].y << " "
                                           << color[k].z << ", alone " << alone.x << " " << alone.y << " " << alone.z);
                differ += color[k] != alone;
            }
            count_differ += got.shadow != want.shadow || got.secondary != want.secondary;
            total += got;
            ++packets;
        }
    INFO(name << ": " << packets << " packets, " << packed << " traced as packets, " << total.shadow << " shadow and "
              << total.secondary << " secondary rays");
    if (packets_expected) CHECK(packed > packets / 2);
    CHECK(total.shadow > packets);
    CHECK(total.secondary > packets);
    CHECK(differ == 0);
    CHECK(count_differ == 0);
}

template <class Real>
void check_shade_packet(const Scene& scene, const std::string& name) {
    CommitOptions o;
    o.accuracy.precision = sizeof(Real) == sizeof(double) ? Precision::Double : Precision::Float;
    const PreparedScene p = prepare_scene(scene, o);
    const KdTree tree = build_kd_tree(p.build_input(), KdBuildConfig{});
    check_shade_packet(p, Tracer<Real>(p.geometry<Real>(), &tree, Traversal::Stack), name + ", kd-tree", true);
    const WideBvh bvh = build_wide_bvh(BvhBuildInput{p.object_bounds(), static_cast<std::uint32_t>(p.geometry_f.spheres.size())});
    // A BVH's packets walk its packed nodes: a scene of spheres alone has none, and traces ray by ray.
    const Tracer<Real> wide(p.geometry<Real>(), AccelRef(nullptr, &bvh), Traversal::Stack);
    check_shade_packet(p, wide, name + ", BVH", !p.geometry_f.triangles.empty());
}

}  // namespace

TEST_CASE("whitted packets: each lane shades as its ray alone, with mirrors and glass", "[render][packets]") {
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        check_shade_packet<float>(mirrors_and_glass_scene(seed), "mirrors and glass " + std::to_string(seed));
        check_shade_packet<double>(mirrors_and_glass_scene(seed), "mirrors and glass (double) " + std::to_string(seed));
    }
}

TEST_CASE("whitted packets: the study scenes with mirrors and glass shade as single rays", "[render][packets]") {
    for (const char* name : {"insane", "lens", "ball-o-calypse"}) {
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        check_shade_packet<float>(scene, name);
    }
}
