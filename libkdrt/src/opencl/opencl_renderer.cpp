#include "opencl/opencl_renderer.h"

#include "cpu/mailbox.h"
#include "opencl/cl_error.h"
#include "opencl/embedded_cl.h"
#include "opencl/program_cache.h"
#include "opencl/ray_order.h"

#include <kdrt/camera.h>
#include <kdrt/error.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>

namespace kdrt::detail {

KernelVariant kernel_variant(const PreparedScene& scene, const RenderOptions& options, bool device_fp64) {
    KernelVariant v;
    v.features = scene.features;
    v.traversal = options.traversal;
    v.fp64 = device_fp64;
    v.normals = !scene.geometry_f.normals.empty();  // the same in both precisions
    v.precision = options.precision;
    v.triangle_test = options.triangle_test;
    v.sphere_test = options.sphere_test;
    v.self_intersection = options.self_intersection;
    v.fixed_epsilon = options.fixed_epsilon;
    return v;
}

std::string kernel_options(const KernelVariant& v) {
    const SceneFeatures& f = v.features;
    std::string o = "-DKDRT_TRAVERSAL=" + std::to_string(static_cast<int>(v.traversal));
    if (f.spheres) o += " -DKDRT_HAS_SPHERES";
    if (f.triangles) o += " -DKDRT_HAS_TRIANGLES";
    if (f.triangles && v.normals) o += " -DKDRT_HAS_NORMALS";
    if (f.lights) o += " -DKDRT_HAS_LIGHTS";
    if (f.max_depth > 1 && f.reflection) o += " -DKDRT_HAS_REFLECTION";
    if (f.max_depth > 1 && f.refraction) o += " -DKDRT_HAS_REFRACTION";
    o += " -DKDRT_MAX_DEPTH=" + std::to_string(f.max_depth);
    if (v.fp64) o += " -DKDRT_HAS_FP64";
    if (v.precision == Precision::Double) o += " -DKDRT_DOUBLE";
    if (v.mailbox) o += " -DKDRT_MAILBOX";
    if (v.triangle_test == TriangleTest::MollerTrumbore) o += " -DKDRT_MOLLER_TRUMBORE";
    if (v.sphere_test == SphereTest::Textbook) o += " -DKDRT_TEXTBOOK_SPHERE";
    if (v.self_intersection == SelfIntersection::FixedEpsilon) {
        char eps[64];
        std::snprintf(eps, sizeof eps, " -DKDRT_FIXED_EPSILON=%.17g", v.fixed_epsilon);
        o += eps;
    }
    return o;
}

namespace {

static_assert(static_cast<int>(Traversal::None) == 0 && static_cast<int>(Traversal::Restart) == 1 &&
                  static_cast<int>(Traversal::Ropes) == 2 && static_cast<int>(Traversal::Stack) == 3,
              "KDRT_TRAVERSAL numbers in cl/common.cl");

template <class T, class V>
void put3(T* dst, const V& v) {
    dst[0] = static_cast<T>(v.x);
    dst[1] = static_cast<T>(v.y);
    dst[2] = static_cast<T>(v.z);
}

// The buffer records of each precision (kdrt_shared.h).
template <class Real>
struct GpuRecords;
template <>
struct GpuRecords<float> {
    using Sphere = GpuSphere;
    using Triangle = GpuTriangle;
    using QueuedRay = GpuRay;
    using Camera = GpuCamera;
    using Light = GpuLight;
};
template <>
struct GpuRecords<double> {
    using Sphere = GpuSphereD;
    using Triangle = GpuTriangleD;
    using QueuedRay = GpuRayD;
    using Camera = GpuCameraD;
    using Light = GpuLightD;
};

// A read-only buffer holding `data` (one dummy element when empty: OpenCL
// has no zero-sized buffers), checked against the device's limits first.
template <class T>
cl::Buffer upload(const cl::Context& ctx, const ocl::ClDevice& dev, const std::vector<T>& data, const char* what) {
    const std::size_t bytes = std::max<std::size_t>(1, data.size()) * sizeof(T);
    ocl::check_allocation(dev, bytes, what);
    std::vector<T> one(1);
    const void* src = data.empty() ? static_cast<const void*>(one.data()) : static_cast<const void*>(data.data());
    return cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(src));
}

template <class Real>
class OpenClRender {
    using Records = GpuRecords<Real>;

public:
    OpenClRender(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options,
                 const ocl::ClDevice& device)
        : scene_(scene), tree_(tree), opt_(options), dev_(device) {}

    RenderResult run() {
        RenderResult result;
        result.features = scene_.features;
        const int W = scene_.settings.width, H = scene_.settings.height, N = scene_.settings.samples;
        const std::size_t pixels = static_cast<std::size_t>(W) * H;
        if (opt_.traversal != Traversal::None && !tree_)
            throw Error(ErrorCode::InvalidArgument, "traversal needs a kd-tree");
        if (opt_.precision == Precision::Double && !dev_.info.fp64)
            throw Error(ErrorCode::Unsupported, "--precision double needs a device with fp64; " + dev_.info.id +
                                                    " (" + dev_.info.name + ") has none");

        ctx_ = cl::Context(dev_.device);
        queue_ = cl::CommandQueue(ctx_, dev_.device);
        KernelVariant variant = kernel_variant(scene_, opt_, dev_.info.fp64);
        variant.mailbox = opt_.traversal != Traversal::None && tree_duplicates_objects(tree_);
        result.kernel_options = kernel_options(variant);
        ocl::ProgramCache cache(opt_.kernel_cache_dir);
        ocl::BuiltProgram built = cache.build(ctx_, dev_, ocl::assemble_kernel_source(), result.kernel_options);
        result.compile_ms = built.compile_ms;
        result.kernel_cache_hit = built.cache_hit;
        if (!cache.problem().empty()) result.warnings.push_back(cache.problem());
        if (!built.cache_warning.empty()) result.warnings.push_back(built.cache_warning);
        program_ = built.program;

        const auto upload_start = std::chrono::steady_clock::now();
        upload_scene();
        queue_.finish();
        result.upload_ms = ms_since(upload_start);
        const auto start = std::chrono::steady_clock::now();

        // Output buffers.
        ocl::check_allocation(dev_, pixels * 3 * sizeof(float), "the image");
        accum_ = cl::Buffer(ctx_, CL_MEM_READ_WRITE, pixels * 3 * sizeof(float));
        queue_.enqueueFillBuffer(accum_, 0.0f, 0, pixels * 3 * sizeof(float));
        const std::size_t id_count = opt_.want_ids ? pixels : 1;
        ids_ = cl::Buffer(ctx_, CL_MEM_WRITE_ONLY, id_count * sizeof(std::int32_t));
        hit_t_ = cl::Buffer(ctx_, CL_MEM_WRITE_ONLY, id_count * sizeof(float));
        counters_ = cl::Buffer(ctx_, CL_MEM_READ_WRITE, 3 * sizeof(std::uint32_t));
        const std::vector<std::uint32_t> order = pixel_order(W, H, opt_.ray_order);
        order_ = upload(ctx_, dev_, order, "the pixel order");

        // Queue capacity per bounce level: every launch takes at most half of
        // it, so the next level (two rays per ray at most) always fits. 2^18
        // rays (12 MiB in float) keep a GPU busy per launch; the queues of all
        // levels together stay within a quarter of the device's memory.
        levels_.resize(static_cast<std::size_t>(scene_.features.max_depth));
        const std::size_t ray_bytes = sizeof(typename Records::QueuedRay);
        const std::uint64_t queue_budget = std::min<std::uint64_t>(dev_.info.global_memory / 4, std::uint64_t{1} << 30);
        capacity_ = std::min<std::size_t>(std::size_t{1} << 18, std::max<std::size_t>(2, 2 * pixels));
        while (capacity_ > 1024 && (capacity_ * ray_bytes > dev_.info.max_allocation ||
                                    capacity_ * ray_bytes * levels_.size() > queue_budget))
            capacity_ /= 2;
        ocl::check_total(dev_, bytes_planned(pixels));

        generate_ = cl::Kernel(program_, "generate_camera_rays");
        trace_ = cl::Kernel(program_, opt_.schedule == Schedule::Persistent ? "trace_persistent" : "trace_plain");
        local_ = opt_.local_size > 0 ? static_cast<std::size_t>(opt_.local_size) : default_local_size();
        const std::size_t max_wg = dev_.device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
        if (local_ > max_wg)
            throw Error(ErrorCode::InvalidArgument, "local size " + std::to_string(local_) +
                                                        " exceeds the device's maximum work-group size " +
                                                        std::to_string(max_wg));
        const std::size_t per_unit = opt_.work_groups_per_unit > 0 ? static_cast<std::size_t>(opt_.work_groups_per_unit) : 4;
        persistent_groups_ = std::max<std::size_t>(1, dev_.info.compute_units * per_unit);

        const typename Records::Camera cam = make_camera(W, H);
        const std::size_t total = pixels * static_cast<std::size_t>(N);
        std::size_t done = 0;
        for (int s = 0; s < N; ++s) {
            double sx, sy;
            sample_offset(s, N, sx, sy);
            for (std::size_t first = 0; first < pixels;) {
                const std::size_t take = std::min(pixels - first, launch_size());
                level_buffer(0);
                generate_.setArg(0, cam);
                generate_.setArg(1, order_);
                generate_.setArg(2, static_cast<cl_uint>(first));
                generate_.setArg(3, static_cast<cl_uint>(take));
                generate_.setArg(4, static_cast<Real>(sx));
                generate_.setArg(5, static_cast<Real>(sy));
                generate_.setArg(6, Real(1) / static_cast<Real>(N));
                generate_.setArg(7, levels_[0]);
                queue_.enqueueNDRangeKernel(generate_, cl::NullRange, cl::NDRange(round_up(take, local_)),
                                            cl::NDRange(local_));
                rays_.camera += take;
                drain(0, take, s == 0 && opt_.want_ids);
                first += take;
                done += take;
                if (opt_.progress) opt_.progress(static_cast<double>(done) / static_cast<double>(total));
            }
        }

        result.image = Image(W, H);
        queue_.enqueueReadBuffer(accum_, CL_TRUE, 0, pixels * 3 * sizeof(float), result.image.rgb.data());
        if (opt_.want_ids) {
            result.ids.resize(pixels);
            result.hit_t.resize(pixels);
            queue_.enqueueReadBuffer(ids_, CL_TRUE, 0, pixels * sizeof(std::int32_t), result.ids.data());
            queue_.enqueueReadBuffer(hit_t_, CL_TRUE, 0, pixels * sizeof(float), result.hit_t.data());
        }
        result.render_ms = ms_since(start);
        result.rays = rays_;
        result.launches = launches_;
        result.device_name = dev_.info.id + " (" + dev_.info.name + ", " + dev_.info.platform + ")";
        return result;
    }

private:
    static std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

    static double ms_since(std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    }

    std::size_t default_local_size() const { return dev_.info.type == "gpu" ? 64 : 16; }

    // Rays per launch: half a queue, and no more than fits in max_launch_ms at
    // the rate measured so far (display drivers kill long kernels).
    std::size_t launch_size() const {
        std::size_t n = capacity_ / 2;
        if (rays_per_ms_ > 0.0 && opt_.max_launch_ms > 0.0) {
            const double fit = rays_per_ms_ * opt_.max_launch_ms * 0.8;
            n = std::min(n, static_cast<std::size_t>(std::max(1024.0, fit)));
        } else {
            n = std::min<std::size_t>(n, 16384);  // a first, modest launch measures the rate
        }
        return std::max<std::size_t>(1, n);
    }

    std::uint64_t bytes_planned(std::size_t pixels) const {
        std::uint64_t b = pixels * (3 * sizeof(float) + sizeof(std::uint32_t));
        if (opt_.want_ids) b += pixels * 8;
        b += static_cast<std::uint64_t>(capacity_) * sizeof(typename Records::QueuedRay) * levels_.size();
        return b + scene_bytes_;
    }

    // Queues are allocated on first use: a scene whose rays die early never
    // pays for its deeper levels. levels_ is sized once, so references stay valid.
    cl::Buffer& level_buffer(std::size_t level) {
        if (levels_[level]() == nullptr) {
            ocl::check_allocation(dev_, capacity_ * sizeof(typename Records::QueuedRay), "a ray queue");
            levels_[level] = cl::Buffer(ctx_, CL_MEM_READ_WRITE, capacity_ * sizeof(typename Records::QueuedRay));
        }
        return levels_[level];
    }

    // Traces the `count` rays at the front of level `level`'s queue, deepest
    // bounces first, so memory stays bounded by one queue per level.
    void drain(std::size_t level, std::size_t count, bool write_ids) {
        const bool bounces = level + 1 < static_cast<std::size_t>(scene_.features.max_depth);
        while (count > 0) {
            const std::size_t take = std::min(count, launch_size());
            count -= take;
            cl::Buffer& out = bounces ? level_buffer(level + 1) : level_buffer(level);
            // Non-blocking: the queue is in order and the blocking read of the
            // counters below waits for this write, so `zero` outlives it.
            const std::uint32_t zero[3] = {0, 0, 0};
            queue_.enqueueWriteBuffer(counters_, CL_FALSE, 0, sizeof zero, zero);
            int a = 0;
            for (cl::Buffer* b : {&spheres_, &triangles_, &normals_, &materials_, &lights_, &nodes_, &leaves_,
                                  &leaf_objects_, &ropes_})
                trace_.setArg(a++, *b);
            trace_.setArg(a++, info_);
            trace_.setArg(a++, levels_[level]);
            trace_.setArg(a++, static_cast<cl_uint>(count));  // the last `take` rays: [count, count + take)
            trace_.setArg(a++, static_cast<cl_uint>(take));
            trace_.setArg(a++, static_cast<cl_uint>(level + 1));
            trace_.setArg(a++, out);
            trace_.setArg(a++, static_cast<cl_uint>(bounces ? capacity_ : 0));
            trace_.setArg(a++, accum_);
            trace_.setArg(a++, ids_);
            trace_.setArg(a++, hit_t_);
            trace_.setArg(a++, static_cast<cl_uint>(write_ids && level == 0 ? 1 : 0));
            trace_.setArg(a++, counters_);
            const std::size_t global = opt_.schedule == Schedule::Persistent
                                           ? std::min(persistent_groups_, (take + local_ - 1) / local_) * local_
                                           : round_up(take, local_);
            const auto t0 = std::chrono::steady_clock::now();
            queue_.enqueueNDRangeKernel(trace_, cl::NullRange, cl::NDRange(global), cl::NDRange(local_));
            std::uint32_t counters[3];
            queue_.enqueueReadBuffer(counters_, CL_TRUE, 0, sizeof counters, counters);
            const double ms = ms_since(t0);
            ++launches_;
            if (ms > 0.0) rays_per_ms_ = rays_per_ms_ > 0.0 ? 0.5 * (rays_per_ms_ + take / ms) : take / ms;
            rays_.shadow += counters[2];
            if (bounces && counters[0] > 0) {
                const std::size_t next = std::min<std::size_t>(counters[0], capacity_);
                rays_.secondary += next;
                drain(level + 1, next, false);
            }
        }
    }

    typename Records::Camera make_camera(int W, int H) const {
        const CameraFrame f(scene_.camera, W, H);
        typename Records::Camera c{};
        put3(c.position, f.position);
        put3(c.forward, f.forward);
        put3(c.right, f.right);
        put3(c.up, f.up);
        c.tan_half_fov = static_cast<Real>(f.tan_half_fov);
        c.aspect = static_cast<Real>(f.aspect);
        c.width = static_cast<std::uint32_t>(W);
        c.height = static_cast<std::uint32_t>(H);
        return c;
    }

    // A read-only buffer of `count` records (one dummy when empty), written in
    // place by fill(T* records) through a mapping: records go straight into
    // the device's memory, with no host vector in between.
    template <class T, class Fill>
    cl::Buffer upload_records(std::size_t count, const char* what, Fill&& fill) {
        const std::size_t bytes = std::max<std::size_t>(1, count) * sizeof(T);
        ocl::check_allocation(dev_, bytes, what);
        cl::Buffer buffer(ctx_, CL_MEM_READ_ONLY | CL_MEM_ALLOC_HOST_PTR, bytes);
        auto* records = static_cast<T*>(
            queue_.enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, bytes));
        if (count == 0) std::memset(static_cast<void*>(records), 0, sizeof(T));
        else fill(records);
        queue_.enqueueUnmapMemObject(buffer, records);
        scene_bytes_ += bytes;
        return buffer;
    }

    template <class T>
    cl::Buffer upload_array(const std::vector<T>& data, const char* what) {
        scene_bytes_ += std::max<std::size_t>(1, data.size()) * sizeof(T);
        return upload(ctx_, dev_, data, what);
    }

    void upload_scene() {
        const auto& g = scene_.template geometry<Real>();
        scene_bytes_ = 0;
        spheres_ = upload_records<typename Records::Sphere>(g.spheres.size(), "the spheres", [&](auto* out) {
            for (const auto& s : g.spheres) {
                typename Records::Sphere d{};
                put3(d.center, s.center);
                d.radius = s.radius;
                d.material = s.material;
                *out++ = d;
            }
        });
        triangles_ = upload_records<typename Records::Triangle>(g.triangles.size(), "the triangles", [&](auto* out) {
            for (const auto& t : g.triangles) {
                typename Records::Triangle d{};
                put3(d.v0, t.v0);
                put3(d.v1, t.v1);
                put3(d.v2, t.v2);
                d.material = t.material;
                d.normals = t.normals == kNoNormal ? KDRT_NO_NORMALS : t.normals;
                *out++ = d;
            }
        });
        normals_ = upload_records<Real>(3 * g.normals.size(), "the shading normals", [&](Real* out) {
            for (const auto& n : g.normals) {
                put3(out, n);
                out += 3;
            }
        });
        std::vector<GpuMaterial> materials;
        for (const Material& m : scene_.materials) {
            GpuMaterial d{};
            put3(d.color, m.color);
            d.diffuse = static_cast<float>(m.diffuse);
            d.specular = static_cast<float>(m.specular);
            d.shininess = static_cast<float>(m.shininess);
            d.reflect = static_cast<float>(m.reflect);
            d.transmit = static_cast<float>(m.transmit);
            d.ior = static_cast<float>(m.ior);
            materials.push_back(d);
        }
        std::vector<typename Records::Light> lights;
        for (const PointLight& l : scene_.lights) {
            typename Records::Light d{};
            put3(d.position, l.position);
            put3(d.color, l.color);
            lights.push_back(d);
        }
        materials_ = upload_array(materials, "the materials");
        lights_ = upload_array(lights, "the lights");
        static const KdTree empty_tree;
        const KdTree& t = tree_ ? *tree_ : empty_tree;
        if (opt_.traversal == Traversal::Ropes && !t.has_ropes())
            throw Error(ErrorCode::InvalidArgument, "the ropes traversal needs a kd-tree with ropes");
        nodes_ = upload_array(t.nodes, "the kd-tree nodes");
        leaves_ = upload_array(t.leaves, "the kd-tree leaves");
        leaf_objects_ = upload_array(t.leaf_objects, "the kd-tree leaf lists");
        ropes_ = upload_array(t.ropes, "the kd-tree ropes");

        info_ = GpuSceneInfo{};
        put3(info_.background, scene_.settings.background);
        put3(info_.ambient, scene_.settings.ambient);
        info_.sphere_count = static_cast<std::uint32_t>(g.spheres.size());
        info_.triangle_count = static_cast<std::uint32_t>(g.triangles.size());
        info_.light_count = static_cast<std::uint32_t>(lights.size());
        info_.leaf_count = static_cast<std::uint32_t>(t.leaves.size());
        put3(info_.box_min, t.bounds.empty() ? glm::dvec3(0.0) : t.bounds.lo);
        put3(info_.box_max, t.bounds.empty() ? glm::dvec3(0.0) : t.bounds.hi);
    }

    const PreparedScene& scene_;
    const KdTree* tree_;
    const RenderOptions& opt_;
    const ocl::ClDevice& dev_;
    cl::Context ctx_;
    cl::CommandQueue queue_;
    cl::Program program_;
    cl::Kernel generate_, trace_;
    cl::Buffer spheres_, triangles_, normals_, materials_, lights_, nodes_, leaves_, leaf_objects_, ropes_;
    cl::Buffer accum_, ids_, hit_t_, counters_, order_;
    std::vector<cl::Buffer> levels_;
    GpuSceneInfo info_{};
    std::size_t capacity_ = 0, local_ = 16, persistent_groups_ = 8;
    std::uint64_t scene_bytes_ = 0;
    double rays_per_ms_ = 0.0;
    RayCounts rays_;
    int launches_ = 0;
};

}  // namespace

RenderResult render_opencl(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options,
                           const ocl::ClDevice& device) {
    return ocl::guard_cl("OpenCL render on " + device.info.id, [&] {
        if (options.precision == Precision::Double) return OpenClRender<double>(scene, tree, options, device).run();
        return OpenClRender<float>(scene, tree, options, device).run();
    });
}

}  // namespace kdrt::detail
