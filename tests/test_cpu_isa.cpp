// The cpu device's hot loops are compiled for two instruction sets (baseline
// SSE2 and AVX2, libkdrt/src/cpu/cpu_isa.h) from the same source, with no
// fused multiply-adds: the two copies must render the same pictures, bit for
// bit, on every traversal of both structures, in both precisions, on the study's scenes and the
// numerically hard ones; and the ray queries must return the same hits.
#include "api_test_scenes.h"
#include "walks.h"

#include "cpu/cpu_isa.h"

#include <kdrt/ray_query.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <cstdlib>
#include <cstring>
#include <optional>
#include <random>
#include <string>

namespace {

// Sets KDRT_CPU_ISA for one scope (the renderer reads it at each render).
class ForcedIsa {
public:
    explicit ForcedIsa(const char* value) {
        if (const char* old = std::getenv("KDRT_CPU_ISA")) old_ = old;
        if (value) setenv("KDRT_CPU_ISA", value, 1);
        else unsetenv("KDRT_CPU_ISA");
    }
    ~ForcedIsa() {
        if (old_) setenv("KDRT_CPU_ISA", old_->c_str(), 1);
        else unsetenv("KDRT_CPU_ISA");
    }
    ForcedIsa(const ForcedIsa&) = delete;
    ForcedIsa& operator=(const ForcedIsa&) = delete;

private:
    std::optional<std::string> old_;
};

kdrt::RenderResult render_in(const char* isa, const kdrt::Scene& scene, const kdrt::RenderOptions& o) {
    const ForcedIsa forced(isa);
    return kdrt::render(scene, o);
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("cpu isa: KDRT_CPU_ISA=baseline selects the SSE2 copy, and the device name says which", "[render][isa]") {
    const kdrt::Scene scene = kdrt::load_scene(std::string(KDRT_SCENES_DIR) + "/lens.json");
    kdrt::RenderOptions o;
    o.frame.width = o.frame.height = 16;
    const kdrt::RenderResult baseline = render_in("baseline", scene, o);
    CHECK(baseline.stats.device_name.find("sse2") != std::string::npos);
    const kdrt::RenderResult best = render_in(nullptr, scene, o);
    const bool avx2 = kdrt::detail::cpu_isa() == kdrt::detail::CpuIsa::Avx2;
    CHECK(best.stats.device_name.find(avx2 ? "avx2" : "sse2") != std::string::npos);
}

TEST_CASE("cpu isa: the AVX2 copy renders bit for bit what the baseline copy renders", "[render][isa][slow]") {
    if (kdrt::detail::cpu_isa() != kdrt::detail::CpuIsa::Avx2) {
        WARN("this processor (or this compiler's build) has no AVX2 copy: nothing to compare");
        return;
    }
    const std::string dir = KDRT_SCENES_DIR;
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse", "hard/insane-shrunk-1e-3",
                             "hard/inside-sphere", "hard/lens-moved-1e5"}) {
        const kdrt::Scene scene = kdrt::load_scene(dir + "/" + name + ".json");
        for (const kdrt_test::Walk walk : kdrt_test::kAllWalks)
            for (auto precision : {kdrt::Precision::Float, kdrt::Precision::Double}) {
                kdrt::RenderOptions o;
                o.frame.width = o.frame.height = 40;
                walk.apply(o.commit);
                o.commit.accuracy.precision = precision;
                o.frame.want_ids = true;
                const kdrt::RenderResult a = render_in("baseline", scene, o), b = render_in(nullptr, scene, o);
                INFO(name << ", " << walk << ", " << (precision == kdrt::Precision::Double ? "double" : "float"));
                REQUIRE(a.stats.device_name.find("sse2") != std::string::npos);
                REQUIRE(b.stats.device_name.find("avx2") != std::string::npos);
                CHECK(same_bits(a.image.rgb, b.image.rgb));
                CHECK(a.ids == b.ids);
                CHECK(same_bits(a.hit_t, b.hit_t));
                CHECK(a.stats.rays.total() == b.stats.rays.total());
            }
    }
}

TEST_CASE("cpu isa: the AVX2 copy's ray queries return the baseline copy's hits, bit for bit", "[api][isa]") {
    if (kdrt::detail::cpu_isa() != kdrt::detail::CpuIsa::Avx2) {
        WARN("this processor (or this compiler's build) has no AVX2 copy: nothing to compare");
        return;
    }
    const kdrt::Scene scene = kdrt_test::api_scene(3);
    // Random rays and coherent fans (the packet path), some with windows.
    std::mt19937 rng(5);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    const glm::dvec3 c{1000.0, -250.0, 40.0};
    std::vector<kdrt::QueryRay> rays;
    for (int i = 0; i < 4000; ++i) {
        const glm::dvec3 o = c + glm::dvec3(rnd(-7, 7), rnd(-7, 7), -12.0);
        const glm::dvec3 target = c + glm::dvec3(rnd(-4, 4), rnd(-4, 4), rnd(-4, 4));
        const glm::dvec3 d = i % 2 ? target - o : glm::dvec3((i % 64) / 96.0 - 0.33, (i / 64 % 64) / 96.0 - 0.33, 1.0);
        const float t_max = i % 5 ? std::numeric_limits<float>::infinity() : float(rnd(5, 15));
        rays.push_back({{float(o.x), float(o.y), float(o.z)}, 0.0f, {float(d.x), float(d.y), float(d.z)}, t_max});
    }
    const kdrt::Device cpu = kdrt::Device::open("cpu");
    for (const kdrt_test::Walk walk : {kdrt_test::Walk{kdrt::Accel::KdTree, kdrt::Traversal::Stack},
                                       kdrt_test::Walk{kdrt::Accel::KdTree, kdrt::Traversal::Restart},
                                       kdrt_test::Walk{kdrt::Accel::KdTree, kdrt::Traversal::None},
                                       kdrt_test::Walk{kdrt::Accel::Bvh, kdrt::Traversal::Stack}})
        for (auto precision : {kdrt::Precision::Float, kdrt::Precision::Double}) {
            kdrt::CommitOptions o;
            walk.apply(o);
            o.accuracy.precision = precision;
            const kdrt::CommittedScene committed = kdrt::CommittedScene::commit(cpu, scene, o);
            auto query = [&](const char* isa, std::vector<kdrt::QueryHit>& hits, std::vector<std::uint8_t>& blocked) {
                const ForcedIsa forced(isa);
                hits.resize(rays.size());
                blocked.resize(rays.size());
                kdrt::intersect(committed, rays, hits);
                kdrt::occluded(committed, rays, blocked);
            };
            std::vector<kdrt::QueryHit> a, b;
            std::vector<std::uint8_t> blocked_a, blocked_b;
            query("baseline", a, blocked_a);
            query(nullptr, b, blocked_b);
            std::size_t differ = 0, hits = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                differ += std::memcmp(&a[i], &b[i], sizeof(kdrt::QueryHit)) != 0;
                hits += a[i].object != KDRT_NO_HIT;
            }
            INFO(walk << ", " << (precision == kdrt::Precision::Double ? "double" : "float"));
            CHECK(hits > rays.size() / 4);
            CHECK(differ == 0);
            CHECK(blocked_a == blocked_b);
        }
}
