#include "opencl/opencl_backend.h"

#include "common/ms_since.h"
#include "device/query_misses.h"
#include "opencl/cl_error.h"
#include "opencl/cl_frame_renderer.h"
#include "opencl/cl_ray_query.h"
#include "opencl/cl_scene_buffers.h"
#include "opencl/kernel_resources.h"
#include "opencl/kernel_variant.h"

#include <kdrt/error.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <string>

namespace kdrt::detail {

namespace {

class OpenClScene final : public OpenClSceneBackend {
public:
    OpenClScene(std::shared_ptr<ocl::ClDeviceContext> context, const PreparedScene& scene, AccelRef accel,
                const CommitOptions& options, BackendWork& work)
        : context_(std::move(context)), scene_(scene), accel_(accel), options_(options) {
        options_.progress = nullptr;  // the commit's alone
        options_.tree_files = {};     // the structure is the caller's
        const ocl::ClDevice& device = context_->device();
        check_opencl_request(device, accel, options);
        const auto lock = context_->lock();
        ocl::guard_cl("committing a scene on OpenCL device " + device.info.id, [&] {
            const auto start = std::chrono::steady_clock::now();
            work.geometry_upload_bytes +=
                buffers_.upload_geometry(*context_, scene, accel, options.accuracy.precision, options.progress);
            ++work.geometry_uploads;
            work.upload_ms += ms_since(start);
            // The program of the scene's first frame (it depends on the buffers:
            // packed leaves or not); ray queries use whichever was built last.
            // An empty scene's queries need none (they answer on the host):
            // its program is compiled when first needed.
            if (scene.geometry_f.object_count() == 0) return;
            const ocl::ProgramHandle program = program_for();
            if (program.compiled_now) {
                ++work.compiles;
                work.compile_ms += program.compile_ms;
            }
            work.warnings = program.warnings;  // the first frame reports them
        });
    }

    RenderResult render(const FrameOptions& frame) override {
        const auto lock = context_->lock();
        return ocl::guard_cl("OpenCL render on " + context_->device().info.id, [&] {
            const ocl::ProgramHandle program = program_for();
            RenderResult r = ocl::render_frame(*context_, buffers_, program.program, scene_, options_.accuracy.precision,
                                               frame, frame_buffers_);
            OpenClStats& cl = r.stats.opencl;
            cl.kernel_options = last_options_;
            cl.kernel_resources = ocl::kernel_resources(program.program, context_->device().device);
            cl.traversal_stack_bytes = ocl::traversal_stack_bytes(variant_);
            cl.kernel_cache_hit = program.cache_hit;  // how the program was first made, for one kept in memory
            if (program.compiled_now) {
                r.stats.compiles = 1;
                r.stats.compile_ms = program.compile_ms;
            }
            r.warnings.insert(r.warnings.begin(), program.warnings.begin(), program.warnings.end());
            return r;
        });
    }

    void update_shading(BackendWork& work) override {
        const auto lock = context_->lock();
        ocl::guard_cl("updating lights and materials on " + context_->device().info.id, [&] {
            const auto start = std::chrono::steady_clock::now();
            buffers_.upload_shading(*context_, scene_);
            context_->queue().finish();
            ++work.shading_uploads;
            work.upload_ms += ms_since(start);
        });
    }

    std::uint64_t device_bytes() const override { return buffers_.device_bytes(); }

    void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const override {
        if (empty()) return std::fill(hits.begin(), hits.end(), kQueryMiss);
        const auto lock = context_->lock();
        ocl::query_closest(target(), rays, hits);
    }

    void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const override {
        if (empty()) return std::fill(occluded.begin(), occluded.end(), std::uint8_t{0});
        const auto lock = context_->lock();
        ocl::query_any(target(), rays, occluded);
    }

    void count_hits(std::span<const QueryRay> rays, std::span<std::uint32_t> counts) const override {
        if (empty()) return std::fill(counts.begin(), counts.end(), 0u);
        const auto lock = context_->lock();
        ocl::query_count_hits(target(), rays, counts);
    }

    void all_hits(std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                  std::vector<QueryHit>& hits) const override {
        if (empty()) {
            splits.assign(rays.size() + 1, 0);
            hits.clear();
            return;
        }
        const auto lock = context_->lock();
        ocl::query_all_hits(target(), rays, splits, hits);
    }

    void closest_points(std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) const override {
        if (empty()) return std::fill(out.begin(), out.end(), no_closest_point());
        const auto lock = context_->lock();
        ocl::query_closest_points(target(), points, out);
    }

    const ocl::ClDeviceContext& device_context() const override { return *context_; }

    void intersect(cl_mem rays, cl_mem hits, std::size_t count) const override {
        const auto lock = context_->lock();
        // Once per commit: an update of the objects commits a new backend (this one has no refit).
        if (!id_table_uploaded_) {
            ocl::guard_cl("uploading the object id table",
                          [&] { buffers_.upload_id_map(*context_, scene_.name_table()); });
            id_table_uploaded_ = true;
        }
        ocl::query_closest(target(), rays, hits, count);
    }

    void occluded(cl_mem rays, cl_mem occluded, std::size_t count) const override {
        const auto lock = context_->lock();
        ocl::query_any(target(), rays, occluded, count);
    }

private:
    // A scene without objects: host-span queries answer without a program.
    bool empty() const { return scene_.geometry_f.object_count() == 0; }

    // The program of the kernel variant for the commit's options and the
    // scene's features as they are now; the caller holds the lock.
    ocl::ProgramHandle program_for() const {
        KernelVariant variant = kernel_variant(scene_, accel_, options_, context_->device().info.fp64);
        variant.cpu_device = cpu_kernels(context_->device());
        variant.exact_divide = exact_divide_sqrt(context_->device());
        variant.packed_leaves = buffers_.leaves_packed();
        last_options_ = kernel_options(variant);
        ocl::ProgramHandle program = context_->program(last_options_, options_.kernel_cache_dir);
        program_ = program.program;
        variant_ = variant;
        rays_per_item_ = rays_per_work_item(variant);  // with the program its queries launch
        return program;
    }

    // Every program of the scene holds the query kernels, specialised for
    // its geometry, traversal, precision and tests alike (the lights and
    // bounce options do not touch them), so queries take the last one.
    ocl::QueryTarget target() const {
        if (!program_()) program_for();  // an empty scene's, on its first query into cl_mem buffers
        ocl::QueryTarget t;
        t.device = context_.get();
        t.buffers = &buffers_;
        t.program = program_;
        t.fp64 = context_->device().info.fp64;
        t.frame_origin = scene_.frame_origin;
        t.max_launch_ms = options_.max_query_launch_ms;
        t.rays_per_item = rays_per_item_;
        t.repeats_objects = variant_.mailbox;
        return t;
    }

    std::shared_ptr<ocl::ClDeviceContext> context_;
    const PreparedScene& scene_;
    AccelRef accel_;         // the BVH where it has one (as the cpu device), else the kd-tree
    CommitOptions options_;  // the commit's (progress dropped): traversal, accuracy, kernel cache, query launches
    // Under the device's lock: the buffers (the id table is added by a const query).
    mutable ocl::ClSceneBuffers buffers_;
    ocl::FrameBuffers frame_buffers_;  // the last frames' image, queues and pixel table
    mutable bool id_table_uploaded_ = false;  // the application's ids in buffers_, for queries on cl_mem
    // The last program built, under the device's lock (built by a const query for an empty scene).
    mutable cl::Program program_;
    mutable std::string last_options_;
    mutable KernelVariant variant_;       // program_'s
    mutable unsigned rays_per_item_ = 1;  // of program_'s variant
};

class OpenClDevice final : public DeviceBackend {
public:
    explicit OpenClDevice(std::shared_ptr<ocl::ClDeviceContext> context) : context_(std::move(context)) {}

    const DeviceInfo& info() const override { return context_->device().info; }
    bool is_opencl() const override { return true; }
    // A GPU's kernels test one triangle at a time, a CPU device's four
    // (cl/visit_objects.cl); both keep the generic cost, since PoCL's lanes
    // are not the cpu device's SIMD leaf test that its lower cost stands for.
    double triangle_cost() const override { return KdBuildConfig::kGenericTriangleCost; }

    std::unique_ptr<SceneBackend> commit(const PreparedScene& scene, AccelRef accel, const CommitOptions& options,
                                         BackendWork& work) override {
        return std::make_unique<OpenClScene>(context_, scene, accel, options, work);
    }

private:
    std::shared_ptr<ocl::ClDeviceContext> context_;
};

}  // namespace

std::unique_ptr<DeviceBackend> make_opencl_backend(const ocl::ClDevice& device) {
    return std::make_unique<OpenClDevice>(std::make_shared<ocl::ClDeviceContext>(device));
}

std::unique_ptr<DeviceBackend> make_opencl_backend(std::shared_ptr<ocl::ClDeviceContext> context) {
    return std::make_unique<OpenClDevice>(std::move(context));
}

}  // namespace kdrt::detail
