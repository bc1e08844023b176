// The OpenCL backend as an adapter over render_opencl: every frame makes its
// context, compiles (or loads from the kernel cache) and uploads the scene
// again, so nothing is kept between frames yet. Ray queries are not
// implemented on OpenCL yet (kdrt::Error(Unsupported)).
#include "opencl/opencl_backend.h"

#include "opencl/opencl_renderer.h"

#include <kdrt/error.h>

namespace kdrt::detail {

namespace {

// Bytes render_opencl copies of the geometry and the tree each frame.
std::uint64_t geometry_bytes(const PreparedScene& scene, const KdTree* tree) {
    const auto& g = scene.geometry_f;
    std::uint64_t bytes = g.spheres.size() * sizeof(GpuSphere) + g.triangles.size() * sizeof(GpuTriangle) +
                          g.normals.size() * 3 * sizeof(float);
    if (tree)
        bytes += tree->nodes.size() * sizeof(KdNode) + tree->leaves.size() * sizeof(KdLeaf) +
                 tree->leaf_objects.size() * sizeof(std::uint32_t) + tree->ropes.size() * sizeof(KdLeafRopes);
    return bytes;
}

class OpenClSceneAdapter final : public SceneBackend {
public:
    OpenClSceneAdapter(const PreparedScene& scene, const KdTree* tree, const ocl::ClDevice& device)
        : scene_(scene), tree_(tree), device_(device) {}

    RenderResult render(const RenderOptions& options) override {
        RenderResult r = render_opencl(scene_, tree_, options, device_);
        r.compiles = 1;
        r.geometry_upload_bytes = geometry_bytes(scene_, tree_);
        return r;
    }

    void update_shading(BackendWork&) override {}  // each frame uploads everything

    void intersect(std::span<const QueryRay>, std::span<QueryHit>) const override { unsupported(); }
    void occluded(std::span<const QueryRay>, std::span<std::uint8_t>) const override { unsupported(); }

private:
    [[noreturn]] void unsupported() const {
        throw Error(ErrorCode::Unsupported, "ray queries on " + device_.info.id + " (" + device_.info.name +
                                                ") are not implemented yet; commit the scene on device \"cpu\"");
    }

    const PreparedScene& scene_;
    const KdTree* tree_;
    const ocl::ClDevice& device_;
};

class OpenClDeviceAdapter final : public DeviceBackend {
public:
    explicit OpenClDeviceAdapter(const ocl::ClDevice& device) : device_(device) {}

    const DeviceInfo& info() const override { return device_.info; }
    bool is_opencl() const override { return true; }

    std::unique_ptr<SceneBackend> commit(const PreparedScene& scene, const KdTree* tree, const RenderOptions&,
                                         BackendWork&) override {
        return std::make_unique<OpenClSceneAdapter>(scene, tree, device_);
    }

private:
    ocl::ClDevice device_;
};

}  // namespace

std::unique_ptr<DeviceBackend> make_opencl_backend(const ocl::ClDevice& device) {
    return std::make_unique<OpenClDeviceAdapter>(device);
}

}  // namespace kdrt::detail
