// The cpu device's hot loops are compiled for two instruction sets (baseline
// SSE2 and AVX2, libkdrt/src/cpu/cpu_isa.h) from the same source, with no
// fused multiply-adds: the two copies must render the same pictures, bit for
// bit, on every traversal, in both precisions, on the study's scenes and the
// numerically hard ones.
#include "cpu/cpu_isa.h"

#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <cstdlib>
#include <cstring>
#include <optional>
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
    o.width = o.height = 16;
    const kdrt::RenderResult baseline = render_in("baseline", scene, o);
    CHECK(baseline.device_name.find("sse2") != std::string::npos);
    const kdrt::RenderResult best = render_in(nullptr, scene, o);
    const bool avx2 = kdrt::detail::cpu_isa() == kdrt::detail::CpuIsa::Avx2;
    CHECK(best.device_name.find(avx2 ? "avx2" : "sse2") != std::string::npos);
}

TEST_CASE("cpu isa: the AVX2 copy renders bit for bit what the baseline copy renders", "[render][isa]") {
    if (kdrt::detail::cpu_isa() != kdrt::detail::CpuIsa::Avx2) {
        WARN("this processor (or this compiler's build) has no AVX2 copy: nothing to compare");
        return;
    }
    const std::string dir = KDRT_SCENES_DIR;
    for (const char* name : {"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse", "hard/insane-shrunk-1e-3",
                             "hard/inside-sphere", "hard/lens-moved-1e5"}) {
        const kdrt::Scene scene = kdrt::load_scene(dir + "/" + name + ".json");
        for (auto traversal : {kdrt::Traversal::Stack, kdrt::Traversal::ShortStack, kdrt::Traversal::Restart,
                               kdrt::Traversal::Ropes, kdrt::Traversal::None})
            for (auto precision : {kdrt::Precision::Float, kdrt::Precision::Double}) {
                kdrt::RenderOptions o;
                o.width = o.height = 40;
                o.traversal = traversal;
                o.precision = precision;
                o.want_ids = true;
                const kdrt::RenderResult a = render_in("baseline", scene, o), b = render_in(nullptr, scene, o);
                INFO(name << ", traversal " << static_cast<int>(traversal) << ", "
                          << (precision == kdrt::Precision::Double ? "double" : "float"));
                REQUIRE(a.device_name.find("sse2") != std::string::npos);
                REQUIRE(b.device_name.find("avx2") != std::string::npos);
                CHECK(same_bits(a.image.rgb, b.image.rgb));
                CHECK(a.ids == b.ids);
                CHECK(same_bits(a.hit_t, b.hit_t));
                CHECK(a.rays.total() == b.rays.total());
            }
    }
}
