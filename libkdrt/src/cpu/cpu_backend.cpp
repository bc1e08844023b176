// The cpu device: frames by the reference renderer, queries by CpuRayQueries.
// Nothing is uploaded; the scene and tree are used where the dispatch layer keeps them.
#include "cpu/cpu_backend.h"

#include "cpu/ray_queries.h"
#include "cpu/reference_renderer.h"

#include <thread>

namespace kdrt::detail {

namespace {

class CpuScene final : public SceneBackend {
public:
    CpuScene(const PreparedScene& scene, const KdTree* tree, const CommitOptions& options)
        : scene_(scene), tree_(tree), options_(options), queries_(scene, tree, options) {
        options_.progress = nullptr;  // the commit's alone
        options_.tree_files = {};     // the tree is the caller's
    }

    RenderResult render(const FrameOptions& frame) override {
        return render_reference(scene_, tree_, options_, frame);
    }
    void update_shading(BackendWork&) override {}  // shading is read from the PreparedScene each frame
    void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const override {
        queries_.intersect(rays, hits);
    }
    void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const override {
        queries_.occluded(rays, occluded);
    }

private:
    const PreparedScene& scene_;
    const KdTree* tree_;
    CommitOptions options_;  // the commit's (progress dropped): traversal, accuracy
    CpuRayQueries queries_;
};

class CpuDevice final : public DeviceBackend {
public:
    const DeviceInfo& info() const override { return info_; }
    bool is_opencl() const override { return false; }
    // A leaf's triangles four or eight at a time (test_leaf_ray, packed_leaves.h).
    double triangle_cost() const override { return 0.3; }
    std::unique_ptr<SceneBackend> commit(const PreparedScene& scene, const KdTree* tree, const CommitOptions& options,
                                         BackendWork&) override {
        return std::make_unique<CpuScene>(scene, tree, options);
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
