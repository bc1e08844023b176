#include "opencl/cl_frame_renderer.h"

#include "common/ms_since.h"
#include "opencl/cl_error.h"
#include "opencl/command_profile.h"
#include "opencl/gpu_records.h"
#include "opencl/kernel_variant.h"
#include "opencl/ray_order.h"

#include <kdrt/camera.h>
#include <kdrt/error.h>

#include <algorithm>
#include <chrono>
#include <limits>

namespace kdrt::detail::ocl {

namespace {

// The accumulator per pixel: three 64-bit fixed-point sums in units of 2^-32
// (common.cl, atomic_add_fixed), low word first.
constexpr std::size_t kAccumWords = 6;

template <class Real>
class FrameRender {
    using Records = GpuRecords<Real>;

public:
    FrameRender(const ClDeviceContext& device, const ClSceneBuffers& buffers, const cl::Program& program,
                const PreparedScene& scene, Precision precision, const FrameOptions& frame, FrameBuffers& frame_buffers)
        : buffers_(buffers), fb_(frame_buffers), scene_(scene), precision_(precision), frame_(frame),
          cl_(frame.opencl), dev_(device.device()), ctx_(device.context()), queue_(device.queue()), program_(program),
          profile_(frame.opencl.profile_commands) {
        // Profiling needs a queue that has it on: one of the frame's own, after
        // the device's queue has finished the scene's uploads.
        if (profile_.on()) {
            queue_.finish();
            queue_ = cl::CommandQueue(ctx_, dev_.device, CL_QUEUE_PROFILING_ENABLE);
        }
    }

    RenderResult run() {
        const int W = scene_.settings.width, H = scene_.settings.height, N = scene_.settings.samples;
        // The pixels asked for (checked by the dispatch layer). Rays, queues
        // and the accumulator number the region's pixels; a pixel's value
        // does not depend on which others share its launches (fixed-point
        // accumulation, common.cl), so it equals the whole frame's.
        const PixelRect region = frame_.region.value_or(PixelRect{0, 0, W, H});
        const std::size_t pixels = static_cast<std::size_t>(region.width) * region.height;
        if (!buffers_.uploaded() || buffers_.precision() != precision_)
            throw Error(ErrorCode::InvalidArgument, "internal: a frame on scene buffers of another precision");
        // The image and id map are made before the clock starts, as the C++
        // renderer's (render_frame.h): render_ms times the same work on both.
        RenderResult result;
        result.image = Image(region.width, region.height);
        if (frame_.want_ids) {
            result.ids.resize(pixels);
            result.hit_t.resize(pixels);
        }
        const auto start = std::chrono::steady_clock::now();
        plan_schedule(N);
        prepare_outputs(region, pixels);
        size_queues(pixels);
        choose_launch_shape();
        camera_ = make_camera(W, H);
        weight_ = Real(1) / static_cast<Real>(N);
        region_ = region;
        total_ = pixels * static_cast<std::size_t>(N);
        trace_samples(N, pixels, result.image.rgb.data());
        if (frame_.want_ids) read_ids(pixels, result);
        RenderStats& stats = result.stats;
        stats.render_ms = ms_since(start);
        stats.rays = rays_;
        stats.features = scene_.features;
        stats.opencl.launches = launches_;
        if (profile_.on()) stats.opencl.command_times = profile_.totals(&stats.opencl.device_busy_ms);
        stats.device_name = dev_.info.id + " (" + dev_.info.name + ", " + dev_.info.platform + ")";
        return result;
    }

private:
    // How the frame's rays are traced: whole ray trees per work-item or
    // queues per bounce level, persistent threads or not, and whether the
    // kernels write the image themselves.
    void plan_schedule(int samples) {
        levels_.resize(static_cast<std::size_t>(scene_.features.max_depth));
        // A CPU device's work-items trace whole ray trees (trace_trees in
        // cl/render.cl): no bounce queues to write, read and launch.
        trees_ = cl_.schedule == Schedule::Persistent && levels_.size() > 1 && cpu_kernels(dev_);
        // With one sample, a work-item that has a pixel's whole sum (its
        // tree, or its only ray) writes the image itself (to_pixel): no
        // accumulator to fill and resolve.
        rgb_out_ = samples == 1 && (trees_ || levels_.size() == 1);
        persistent_ = cl_.schedule != Schedule::Plain;
    }

    // The frame's output buffers (accumulator, id map, counters) and the
    // camera rays' pixel order.
    void prepare_outputs(const PixelRect& region, std::size_t pixels) {
        if (rgb_out_) {
            sized(fb_.accum, fb_.accum_bytes, kAccumWords * sizeof(cl_uint), "the image");  // an argument, unread
        } else {
            const std::size_t accum_bytes = pixels * kAccumWords * sizeof(cl_uint);
            if (fb_.accum() == nullptr || fb_.accum_bytes < accum_bytes) fb_.accum_zero = false;
            sized(fb_.accum, fb_.accum_bytes, accum_bytes, "the image");
            if (!fb_.accum_zero)  // all of it: a later, larger frame may use the rest
                queue_.enqueueFillBuffer(fb_.accum, cl_uint{0}, 0, fb_.accum_bytes, nullptr,
                                         profile_.event("fill image"));
            fb_.accum_zero = false;  // until this frame's resolve_image has cleared it
        }
        const std::size_t id_count = frame_.want_ids ? pixels : 1;
        sized(fb_.ids, fb_.ids_bytes, id_count * sizeof(std::int32_t), "the id map");
        sized(fb_.hit_t, fb_.hit_t_bytes, id_count * sizeof(float), "the id map");
        sized(fb_.counters, fb_.counters_bytes, 3 * sizeof(std::uint32_t) * std::max(1, scene_.features.max_depth),
              "the counters");
        prepare_pixel_order(region);
    }

    // Rows and tiles on GPUs: the kernel computes each ray's pixel (pixel_at,
    // render.cl). Otherwise a table of pixels, kept while the region and the
    // order stay the same.
    void prepare_pixel_order(const PixelRect& region) {
        if (cl_.ray_order == RayOrder::Morton || cpu_kernels(dev_)) {
            if (fb_.order_width != region.width || fb_.order_height != region.height ||
                fb_.order_kind != cl_.ray_order) {
                const std::vector<std::uint32_t> table = pixel_order(region.width, region.height, cl_.ray_order);
                fb_.order_width = 0;  // until it is written
                sized(fb_.order, fb_.order_bytes, table.size() * sizeof(std::uint32_t), "the pixel order");
                queue_.enqueueWriteBuffer(fb_.order, CL_TRUE, 0, table.size() * sizeof(std::uint32_t), table.data());
                fb_.order_width = region.width;
                fb_.order_height = region.height;
                fb_.order_kind = cl_.ray_order;
            }
            ray_order_ = KDRT_PIXEL_ORDER_TABLE;
        } else {
            sized(fb_.order, fb_.order_bytes, sizeof(cl_uint), "the pixel order");  // unread: any kept table will do
            ray_order_ = cl_.ray_order == RayOrder::Rows ? KDRT_PIXEL_ORDER_ROWS : KDRT_PIXEL_ORDER_TILES;
        }
    }

    // Queue capacity per bounce level: every launch takes at most half of
    // it, so the next level (two rays per ray at most) always fits. 2^18
    // rays (12 MiB in float) keep a GPU busy per launch; the queues of all
    // levels together stay within a quarter of the device's memory. With
    // whole trees it only sizes the camera launches.
    void size_queues(std::size_t pixels) {
        rates_.resize(levels_.size());
        const std::size_t ray_bytes = sizeof(typename Records::QueuedRay);
        const std::uint64_t queue_budget = std::min<std::uint64_t>(dev_.info.global_memory / 4, std::uint64_t{1} << 30);
        capacity_ = std::min<std::size_t>(std::size_t{1} << 18, std::max<std::size_t>(2, 2 * pixels));
        while (capacity_ > 1024 && (capacity_ * ray_bytes > dev_.info.max_allocation ||
                                    capacity_ * ray_bytes * levels_.size() > queue_budget))
            capacity_ /= 2;
        ocl::check_total(dev_, bytes_planned(pixels));
    }

    // The trace kernel, its work-group size and the persistent threads' groups.
    void choose_launch_shape() {
        trace_name_ = trees_ ? "trace_trees" : persistent_ ? "trace_persistent" : "trace_plain";
        trace_ = cl::Kernel(program_, trace_name_);
        local_ = cl_.local_size > 0 ? static_cast<std::size_t>(cl_.local_size) : default_local_size();
        const std::size_t max_wg = dev_.device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
        if (local_ > max_wg)
            throw Error(ErrorCode::InvalidArgument, "local size " + std::to_string(local_) +
                                                        " exceeds the device's maximum work-group size " +
                                                        std::to_string(max_wg));
        const std::size_t per_unit = cl_.work_groups_per_unit > 0 ? static_cast<std::size_t>(cl_.work_groups_per_unit) : 4;
        persistent_groups_ = std::max<std::size_t>(1, dev_.info.compute_units * per_unit);
        chained_ = persistent_ && !trees_ && dev_.info.type == "gpu";
    }

    // Every sample's camera rays in batches, their bounces traced, then the
    // image's floats into `image` (3 per pixel).
    void trace_samples(int samples, std::size_t pixels, float* image) {
        const std::size_t values = pixels * 3;
        try {
            image_target(values, image);
            for (int s = 0; s < samples; ++s) {
                double sx, sy;
                sample_offset(s, samples, sx, sy);
                for (std::size_t first = 0; first < pixels;) {
                    const std::size_t take = std::min(pixels - first, launch_size(0));
                    // The first bounce makes these camera rays itself (render.cl).
                    camera_first_ = first;
                    sx_ = static_cast<Real>(sx);
                    sy_ = static_cast<Real>(sy);
                    rays_.camera += take;
                    if (chained_) chain(take, s == 0 && frame_.want_ids);
                    else drain(0, 0, take, s == 0 && frame_.want_ids);
                    first += take;
                    done_ += take;
                    poll_progress(true);
                }
            }
            if (!rgb_out_) resolve_image(values);
            read_image(values, image);
        } catch (...) {
            // Kernels may still write the image, whose memory may be the
            // caller's (image_target) and is freed as the error unwinds:
            // they finish, and the buffer wrapping it goes first.
            clFinish(queue_());
            rgb_ = cl::Buffer();
            throw;
        }
    }

    void read_ids(std::size_t pixels, RenderResult& result) {
        queue_.enqueueReadBuffer(fb_.ids, CL_TRUE, 0, pixels * sizeof(std::int32_t), result.ids.data(), nullptr,
                                 profile_.event("read ids"));
        queue_.enqueueReadBuffer(fb_.hit_t, CL_TRUE, 0, pixels * sizeof(float), result.hit_t.data(), nullptr,
                                 profile_.event("read ids"));
    }

    static std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

    // Reports progress (after each camera batch; between bounce launches, or
    // after a chain, at most every 50 ms) and cancels when the callback says
    // so. Runs with the queue idle (the launches end in a blocking read), so
    // throwing here leaves nothing in flight on the frame's buffers.
    void poll_progress(bool batch_done) {
        if (!frame_.progress) return;
        const auto now = std::chrono::steady_clock::now();
        if (!batch_done && now - last_poll_ < std::chrono::milliseconds(50)) return;
        last_poll_ = now;
        if (!frame_.progress(static_cast<double>(done_) / static_cast<double>(total_)))
            throw Error(ErrorCode::Cancelled, "OpenCL render cancelled by the progress callback");
    }

    std::size_t default_local_size() const { return dev_.info.type == "gpu" ? 64 : 16; }

    // Rays per launch at a bounce level: half a queue, and no more than fits
    // in max_launch_ms at the rate measured so far (display drivers kill long
    // kernels). The rate is the level's own, over all its launches: the deep
    // levels' few rays per launch are mostly launch overhead, and a rate
    // averaged with theirs had cut the camera rays into many small launches.
    // A chain (GPUs) counts its whole time against its camera rays, and its
    // deeper launches take no more rays than those: a bound on each launch.
    // Launches that queue nothing (whole trees, or no bounces) are bounded
    // by the time alone.
    std::size_t launch_size(std::size_t level) const {
        std::size_t n = queues_bounces(0) ? capacity_ / 2 : std::size_t{std::numeric_limits<cl_uint>::max()};
        // A progress callback may cancel: launches of at most 80 ms keep the answer within ~100 ms.
        const double limit_ms = frame_.progress ? (cl_.max_launch_ms > 0.0 ? std::min(cl_.max_launch_ms, 80.0) : 80.0)
                                              : cl_.max_launch_ms;
        const LaunchRate& r = rates_[level].ms > 0.0 ? rates_[level] : all_levels_;
        if (r.ms > 0.0 && limit_ms > 0.0) {
            const double fit = r.rays / r.ms * limit_ms * 0.8;
            n = std::min(n, static_cast<std::size_t>(std::max(1024.0, fit)));
        } else {
            n = std::min<std::size_t>(n, 16384);  // a first, modest launch measures the rate
        }
        return std::max<std::size_t>(1, n);
    }

    // Whether the rays a launch at `level` spawns wait in the next level's
    // queue: not with whole trees (trace_trees traces them itself), nor at
    // the deepest level.
    bool queues_bounces(std::size_t level) const { return !trees_ && level + 1 < levels_.size(); }

    // The buffer the frame's floats go to, `values` of them, for read_image
    // to hand back in `out`. A device that computes in the host's memory
    // writes `out` itself (a buffer on it, mapped to hand it back) where it
    // can wrap it, a copy of the image less.
    void image_target(std::size_t values, float* out) {
        const std::size_t bytes = values * sizeof(float);
        rgb_ = cl::Buffer();
        if (dev_.host_memory && bytes <= dev_.info.max_allocation) {
            try {
                rgb_ = cl::Buffer(ctx_, CL_MEM_WRITE_ONLY | CL_MEM_USE_HOST_PTR, bytes, out);
            } catch (const cl::Error&) {
                // Declined (alignment rules): rgb_ stays empty, the frame's own buffer serves.
            }
        }
        rgb_in_place_ = rgb_() != nullptr;
        if (!rgb_in_place_) rgb_ = sized(fb_.rgb, fb_.rgb_bytes, bytes, "the image");
    }

    // The accumulator's sums as the image's floats (resolve_image in
    // render.cl); the sums read are left zero for the next frame.
    void resolve_image(std::size_t values) {
        cl::Kernel resolve(program_, "resolve_image");
        resolve.setArg(0, fb_.accum);
        resolve.setArg(1, rgb_);
        resolve.setArg(2, static_cast<cl_ulong>(values));
        const std::size_t local =
            std::min<std::size_t>(64, resolve.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(dev_.device));
        queue_.enqueueNDRangeKernel(resolve, cl::NullRange, cl::NDRange(round_up(values, local)), cl::NDRange(local),
                                    nullptr, profile_.event("resolve image"));
    }

    // The image's floats into `out`, the memory image_target was given.
    void read_image(std::size_t values, float* out) {
        const std::size_t bytes = values * sizeof(float);
        if (rgb_in_place_) {
            void* mapped =
                queue_.enqueueMapBuffer(rgb_, CL_TRUE, CL_MAP_READ, 0, bytes, nullptr, profile_.event("read image"));
            queue_.enqueueUnmapMemObject(rgb_, mapped);
            queue_.finish();
        } else {
            queue_.enqueueReadBuffer(rgb_, CL_TRUE, 0, bytes, out, nullptr, profile_.event("read image"));
        }
        if (!rgb_out_) fb_.accum_zero = true;  // resolve_image, which this read waited for, cleared it
        rgb_ = cl::Buffer();  // before the memory it may wrap goes back to the caller
    }

    std::uint64_t bytes_planned(std::size_t pixels) const {
        // The accumulator (unless the kernels write the image), the image and the pixel table
        // (KDRT_PIXEL_ORDER_TABLE).
        std::uint64_t b = pixels * ((rgb_out_ ? 0 : kAccumWords * sizeof(cl_uint)) + 3 * sizeof(float));
        if (ray_order_ == KDRT_PIXEL_ORDER_TABLE) b += pixels * sizeof(std::uint32_t);
        if (frame_.want_ids) b += pixels * 8;
        if (!trees_) b += static_cast<std::uint64_t>(capacity_) * sizeof(typename Records::QueuedRay) * levels_.size();
        return b + buffers_.device_bytes();
    }

    // `buffer` (of frame_buffers) with room for `bytes`: kept from an earlier
    // frame when it has, else made anew (the old one released first).
    cl::Buffer& sized(cl::Buffer& buffer, std::size_t& have, std::size_t bytes, const char* what) {
        if (buffer() == nullptr || have < bytes) {
            buffer = cl::Buffer();
            have = 0;
            ocl::check_allocation(dev_, bytes, what);
            buffer = cl::Buffer(ctx_, CL_MEM_READ_WRITE, bytes);
            have = bytes;
        }
        return buffer;
    }

    // Queues are taken on first use: on a CPU device a scene whose rays die
    // early never pays for its deeper levels (a chain takes them all at
    // once). levels_ is sized once, so references stay valid.
    cl::Buffer& level_buffer(std::size_t level) {
        if (levels_[level]() == nullptr) {
            const std::size_t bytes = capacity_ * sizeof(typename Records::QueuedRay);
            if (fb_.level_bytes < bytes) {  // the kept queues are too small: none is kept
                fb_.levels.clear();
                fb_.level_bytes = bytes;
            }
            if (fb_.levels.size() <= level) fb_.levels.resize(level + 1);
            cl::Buffer& kept = fb_.levels[level];
            if (kept() == nullptr) {
                ocl::check_allocation(dev_, fb_.level_bytes, "a ray queue");
                kept = cl::Buffer(ctx_, CL_MEM_READ_WRITE, fb_.level_bytes);
            }
            levels_[level] = kept;
        }
        return levels_[level];
    }

    // Traces rays [first, first + count) of level `level`'s queue, the last
    // ones first and deeper bounces before the rest, so memory stays bounded
    // by one queue per level; the host reads the counters after each launch.
    void drain(std::size_t level, std::size_t first, std::size_t count, bool write_ids) {
        const bool bounces = queues_bounces(level);
        while (count > 0) {
            const std::size_t take = std::min(count, launch_size(level));
            count -= take;
            // Non-blocking: the queue is in order and the blocking read of the
            // counters below waits for this write, so `zero` outlives it.
            const std::uint32_t zero[3] = {0, 0, 0};
            queue_.enqueueWriteBuffer(fb_.counters, CL_FALSE, slot_offset(level), sizeof zero, zero, nullptr,
                                      profile_.event("write counters"));
            const auto t0 = std::chrono::steady_clock::now();
            enqueue_trace(level, first + count, take, false, write_ids);
            std::uint32_t counters[3];
            queue_.enqueueReadBuffer(fb_.counters, CL_TRUE, slot_offset(level), sizeof counters, counters, nullptr,
                                     profile_.event("read counters"));
            note_rate(level, take, ms_since(t0));
            rays_.shadow += counters[2];
            if (trees_) rays_.secondary += counters[0];
            poll_progress(false);
            if (bounces && counters[0] > 0) {
                const std::size_t next = std::min<std::size_t>(counters[0], capacity_);
                rays_.secondary += next;
                drain(level + 1, 0, next, false);
            }
        }
    }

    // GPUs: a camera batch's levels are enqueued back to back, each launch
    // taking the rays the level before appended (counted on the device), and
    // the counters are read once at the end instead of after every launch as
    // drain() does, which saves a host round trip per level. A deeper launch takes at most `take` rays
    // (launch_size: a bound on its time); a level that received more keeps
    // the rest in its queue, and drain() traces those afterwards, deepest
    // level first, so that no queue is overwritten before it is read. Every
    // level is launched, empty or not.
    void chain(std::size_t take, bool write_ids) {
        const std::size_t depth = levels_.size();
        for (std::size_t level = 1; level < depth; ++level) level_buffer(level);  // before anything is in flight
        queue_.enqueueFillBuffer(fb_.counters, cl_uint{0}, 0, slot_offset(depth), nullptr, profile_.event("write counters"));
        const auto t0 = std::chrono::steady_clock::now();
        for (std::size_t level = 0; level < depth; ++level) enqueue_trace(level, 0, take, level > 0, write_ids);
        std::vector<std::uint32_t> counters(3 * depth);
        queue_.enqueueReadBuffer(fb_.counters, CL_TRUE, 0, slot_offset(depth), counters.data(), nullptr,
                                 profile_.event("read counters"));
        note_rate(0, take, ms_since(t0));  // the whole chain's time: a bound on each launch's
        std::vector<std::size_t> appended(depth, 0);  // by the level that traces them
        for (std::size_t level = 0; level < depth; ++level) {
            rays_.shadow += counters[3 * level + 2];
            if (level + 1 < depth) {
                appended[level + 1] = std::min<std::size_t>(counters[3 * level], capacity_);
                rays_.secondary += appended[level + 1];
            }
        }
        poll_progress(false);
        for (std::size_t level = depth; level-- > 1;) {
            const std::size_t traced = std::min(appended[level], take);
            if (appended[level] > traced) drain(level, traced, appended[level] - traced, false);
        }
    }

    // Byte offset of a bounce level's three counters.
    static std::size_t slot_offset(std::size_t level) { return 3 * sizeof(std::uint32_t) * level; }

    void note_rate(std::size_t level, std::size_t rays, double ms) {
        if (ms <= 0.0) return;
        for (LaunchRate* r : {&rates_[level], &all_levels_}) {
            r->rays += static_cast<double>(rays);
            r->ms += ms;
        }
    }

    // Enqueues one launch of level `level` over its queue's rays [first,
    // first + count) (level 0: camera rays), or over at most `count` of them
    // as the level before counted them (`counted`).
    void enqueue_trace(std::size_t level, std::size_t first, std::size_t count, bool counted, bool write_ids) {
        const bool bounces = queues_bounces(level);
        cl::Buffer& out = bounces ? level_buffer(level + 1) : fb_.order;  // no bounce: nothing is appended
        cl_uint a = buffers_.set_scene_args(trace_);
        trace_.setArg(a++, level == 0 ? fb_.order : level_buffer(level));  // level 0: unread, the kernel makes camera rays
        trace_.setArg(a++, static_cast<cl_uint>(first));
        trace_.setArg(a++, static_cast<cl_uint>(count));
        trace_.setArg(a++, static_cast<cl_uint>(level + 1));
        trace_.setArg(a++, out);
        trace_.setArg(a++, static_cast<cl_uint>(bounces ? capacity_ : 0));
        trace_.setArg(a++, fb_.accum);
        trace_.setArg(a++, rgb_);
        trace_.setArg(a++, static_cast<cl_uint>(rgb_out_ ? 1 : 0));
        trace_.setArg(a++, fb_.ids);
        trace_.setArg(a++, fb_.hit_t);
        trace_.setArg(a++, static_cast<cl_uint>(write_ids && level == 0 ? 1 : 0));
        trace_.setArg(a++, fb_.counters);
        trace_.setArg(a++, static_cast<cl_uint>(level));
        trace_.setArg(a++, static_cast<cl_uint>(counted ? 1 : 0));
        // The first bounce's camera rays (KDRT_CAMERA_PARAMS); deeper ones ignore them.
        trace_.setArg(a++, camera_);
        trace_.setArg(a++, fb_.order);
        trace_.setArg(a++, ray_order_);
        trace_.setArg(a++, static_cast<cl_uint>(camera_first_));
        trace_.setArg(a++, sx_);
        trace_.setArg(a++, sy_);
        trace_.setArg(a++, weight_);
        trace_.setArg(a++, static_cast<cl_uint>(region_.x));
        trace_.setArg(a++, static_cast<cl_uint>(region_.y));
        trace_.setArg(a++, static_cast<cl_uint>(region_.width));
        trace_.setArg(a++, static_cast<cl_uint>(region_.height));
        const std::size_t global = persistent_
                                       ? std::min(persistent_groups_, round_up(count, local_) / local_) * local_
                                       : round_up(count, local_);
        queue_.enqueueNDRangeKernel(trace_, cl::NullRange, cl::NDRange(global), cl::NDRange(local_), nullptr,
                                    profile_.event(trace_name_, static_cast<int>(level) + 1));
        ++launches_;
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

    const ClSceneBuffers& buffers_;
    FrameBuffers& fb_;
    const PreparedScene& scene_;
    Precision precision_;
    const FrameOptions& frame_;
    const OpenClExecution& cl_;
    const ClDevice& dev_;
    cl::Context ctx_;
    cl::CommandQueue queue_;
    cl::Program program_;
    CommandProfile profile_;
    cl::Kernel trace_;
    // The camera batch being traced: its first camera ray's index, the sample's offset and weight.
    typename Records::Camera camera_{};
    std::size_t camera_first_ = 0;
    Real sx_ = 0, sy_ = 0, weight_ = 1;
    PixelRect region_;
    const char* trace_name_ = "trace_persistent";
    cl_uint ray_order_ = KDRT_PIXEL_ORDER_ROWS;  // KDRT_PIXEL_ORDER_*: computed, or fb_.order's table
    std::vector<cl::Buffer> levels_;  // this frame's queues (of fb_.levels), by bounce level
    std::size_t capacity_ = 0, local_ = 16, persistent_groups_ = 8;
    bool trees_ = false;       // trace_trees: camera launches only, no queues
    bool rgb_out_ = false;     // the trace kernels write the image, accum is unused
    cl::Buffer rgb_;           // the image's floats (image_target)
    bool rgb_in_place_ = false;  // rgb_ wraps the caller's memory
    bool persistent_ = false;  // persistent threads (trace_trees or trace_persistent)
    bool chained_ = false;  // chain(): the levels' launches without a read between them
    struct LaunchRate {
        double rays = 0.0, ms = 0.0;  // traced so far, and the launches' wall time
    };
    std::vector<LaunchRate> rates_;  // by bounce level
    LaunchRate all_levels_;
    RayCounts rays_;
    int launches_ = 0;
    std::size_t done_ = 0, total_ = 1;
    std::chrono::steady_clock::time_point last_poll_ = std::chrono::steady_clock::now();
};

}  // namespace

RenderResult render_frame(const ClDeviceContext& device, const ClSceneBuffers& buffers, const cl::Program& program,
                          const PreparedScene& scene, Precision precision, const FrameOptions& frame,
                          FrameBuffers& frame_buffers) {
    return guard_cl("OpenCL render on " + device.device().info.id, [&] {
        if (precision == Precision::Double)
            return FrameRender<double>(device, buffers, program, scene, precision, frame, frame_buffers).run();
        return FrameRender<float>(device, buffers, program, scene, precision, frame, frame_buffers).run();
    });
}

}  // namespace kdrt::detail::ocl
