// The cpu device: frames and ray queries through the committed scene's CpuTracing.
// Nothing is uploaded; the scene and tree are used where the dispatch layer keeps them.
#include "cpu/cpu_backend.h"

#include "cpu/cpu_tracing.h"

#include <mutex>
#include <thread>

namespace kdrt::detail {

namespace {

// The scene's tracing is made on first use in each instruction set that
// cpu_isa() picks (KDRT_CPU_ISA may change between calls), then kept.
class CpuScene final : public SceneBackend {
public:
    CpuScene(const PreparedScene& scene, AccelRef accel, const CommitOptions& options)
        : scene_(scene), accel_(accel), options_(options) {
        options_.progress = nullptr;  // the commit's alone
        options_.tree_files = {};     // the tree is the caller's
        tracing();  // a traversal the tree cannot serve is refused at commit
    }

    RenderResult render(const FrameOptions& frame) override { return tracing().render(frame); }
    void update_shading(BackendWork&) override {}  // shading is read from the PreparedScene each frame
    bool refit(BackendWork&) override {
        for (Slot& slot : slots_)
            if (slot.tracing) slot.tracing->refit();
        return true;
    }
    std::uint64_t device_bytes() const override {
        std::uint64_t bytes = 0;
        for (const Slot& slot : slots_)
            if (slot.tracing) bytes += slot.tracing->packed_bytes();
        return bytes;
    }
    void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const override {
        tracing().intersect(rays, hits);
    }
    void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const override {
        tracing().occluded(rays, occluded);
    }
    void count_hits(std::span<const QueryRay> rays, std::span<std::uint32_t> counts) const override {
        tracing().count_hits(rays, counts);
    }
    bool count_hits_once_per_geometry(std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                                      std::span<const std::uint32_t> geometry_of) const override {
        tracing().count_hits_once_per_geometry(rays, counts, geometry_of);
        return true;
    }
    void all_hits(std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                  std::vector<QueryHit>& hits) const override {
        tracing().all_hits(rays, splits, hits);
    }
    void closest_points(std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) const override {
        tracing().closest_points(points, out);
    }

private:
    const CpuTracing& tracing() const {
        const CpuIsa isa = cpu_isa();
        Slot& slot = slots_[isa == CpuIsa::Avx2 ? 1 : 0];
        std::call_once(slot.once, [&] { slot.tracing = make_cpu_tracing(isa, scene_, accel_, options_); });
        return *slot.tracing;
    }

    struct Slot {
        std::once_flag once;
        std::unique_ptr<CpuTracing> tracing;
    };
    const PreparedScene& scene_;
    AccelRef accel_;
    CommitOptions options_;  // the commit's: traversal, accuracy
    mutable Slot slots_[2];  // baseline, AVX2
};

class CpuDevice final : public DeviceBackend {
public:
    const DeviceInfo& info() const override { return info_; }
    bool is_opencl() const override { return false; }
    // A leaf's triangles four or eight at a time (test_leaf_ray, packed_leaves.h).
    double triangle_cost() const override { return 0.3; }
    std::unique_ptr<SceneBackend> commit(const PreparedScene& scene, AccelRef accel, const CommitOptions& options,
                                         BackendWork&) override {
        return std::make_unique<CpuScene>(scene, accel, options);
    }

private:
    DeviceInfo info_ = cpu_device_info();
};

}  // namespace

DeviceInfo cpu_device_info() {
    DeviceInfo cpu;
    cpu.id = "cpu";
    cpu.platform = "C++ reference";
    cpu.name = "kdrt C++ reference renderer";
    cpu.vendor = "kdrt";
    cpu.type = "cpu";
    cpu.driver_version = "built in";
    cpu.compute_units = std::thread::hardware_concurrency();
    cpu.fp64 = true;
    return cpu;
}

std::unique_ptr<DeviceBackend> make_cpu_backend() { return std::make_unique<CpuDevice>(); }

}  // namespace kdrt::detail
