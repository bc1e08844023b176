#include "frames_bench.h"

#include "machine_info.h"
#include "mesh_generator.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "table.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace kdrt::bench {

namespace {

// The camera orbited about its look-at point, around its up axis, by `degrees`.
Camera orbit(const Camera& c, double degrees) {
    const glm::dvec3 axis = glm::normalize(c.up);
    const glm::dvec3 v = c.position - c.look_at;
    const double a = degrees * 3.14159265358979323846 / 180.0;
    // Rodrigues' rotation formula.
    const glm::dvec3 r = v * std::cos(a) + glm::cross(axis, v) * std::sin(a) + axis * glm::dot(axis, v) * (1.0 - std::cos(a));
    Camera moved = c;
    moved.position = c.look_at + r;
    return moved;
}

struct Frame {
    std::vector<double> wall_ms, update_ms, render_ms, build_ms, compile_ms, upload_ms;
    std::uint64_t builds = 0, compiles = 0, upload_bytes = 0;  // of the last run (the same in every run)
};

struct Sequence {
    std::string input, device;
    std::size_t objects = 0;
    std::vector<Frame> frames;
};

class FramesBench {
public:
    explicit FramesBench(const FramesBenchOptions& o) : opt_(o) {}

    int run() {
        devices_ = opt_.devices;
        if (devices_.empty()) {
            devices_.push_back("cpu");
            for (const DeviceInfo& d : list_devices())
                if (d.id != "cpu") {
                    devices_.push_back("opencl");
                    break;
                }
        }
        std::vector<NamedScene> inputs;
        if (!(opt_.scenes.size() == 1 && opt_.scenes.front() == "none")) inputs = load_scenes(opt_.scenes, opt_.scenes_dir);
        for (const std::string& m : opt_.meshes) {
            Scene s = make_generated_scene(m);
            inputs.push_back({s.name, {}, std::move(s)});
        }
        for (const NamedScene& in : inputs)
            for (const std::string& d : devices_) measure(in, d);
        write_outputs();
        return 0;
    }

private:
    void measure(const NamedScene& in, const std::string& device_name) {
        Sequence seq;
        seq.input = in.name;
        seq.device = device_name;
        seq.objects = in.scene.object_count();
        seq.frames.resize(static_cast<std::size_t>(opt_.frames));
        CommitOptions commit_options;
        FrameOptions frame_options;
        if (opt_.size > 0) frame_options.width = frame_options.height = opt_.size;
        if (opt_.intersection_cost > 0.0) commit_options.tree.intersection_cost = opt_.intersection_cost;
        for (int run = 0; run < opt_.runs; ++run) {
            Scene scene = in.scene;
            // Frame 1 from nothing: a fresh device (context, queue, program cache), commit, render.
            Stopwatch clock;
            CommittedScene committed = CommittedScene::commit(Device::open(device_name), scene, commit_options);
            for (int f = 0; f < opt_.frames; ++f) {
                double update_ms = 0.0;
                if (f > 0) {
                    clock.restart();
                    scene.camera = orbit(scene.camera, opt_.step_degrees);
                    committed.update(scene);
                    update_ms = clock.ms();
                }
                const RenderResult r = committed.render(frame_options);
                Frame& fr = seq.frames[static_cast<std::size_t>(f)];
                fr.wall_ms.push_back(clock.ms());
                fr.update_ms.push_back(update_ms);
                fr.render_ms.push_back(r.stats.render_ms);
                fr.build_ms.push_back(r.stats.build_ms);
                fr.compile_ms.push_back(r.stats.compile_ms);
                fr.upload_ms.push_back(r.stats.upload_ms);
                fr.builds = r.stats.builds;
                fr.compiles = r.stats.compiles;
                fr.upload_bytes = r.stats.geometry_upload_bytes;
            }
        }
        for (std::size_t f = 0; f < seq.frames.size(); ++f) {
            const Frame& fr = seq.frames[f];
            std::fprintf(stderr, "%s on %s, frame %zu: %s ms (update %s ms, render %s ms), %llu builds, %llu compiles, %llu bytes uploaded\n",
                         seq.input.c_str(), seq.device.c_str(), f + 1, fmt_ms(median(fr.wall_ms)).c_str(),
                         fmt_ms(median(fr.update_ms)).c_str(), fmt_ms(median(fr.render_ms)).c_str(),
                         static_cast<unsigned long long>(fr.builds),
                         static_cast<unsigned long long>(fr.compiles), static_cast<unsigned long long>(fr.upload_bytes));
        }
        sequences_.push_back(seq);
    }

    void write_outputs() const {
        TextTable t;
        t.header = {"input", "objects", "device", "frame", "wall ms", "update ms", "render ms", "builds", "build ms", "compiles",
                    "compile ms", "geometry upload bytes", "upload ms", "wall / frame 1"};
        TextTable csv;
        csv.header = {"input", "objects", "device", "frame", "wall_ms", "update_ms", "render_ms", "builds", "build_ms", "compiles",
                      "compile_ms", "geometry_upload_bytes", "upload_ms"};
        TextTable summary;
        summary.header = {"input", "device", "frame 1 ms (open + commit + render)",
                          "later frames ms (update + render), median", "update() ms, median", "later frame / frame 1"};
        for (const Sequence& s : sequences_) {
            const double first = median(s.frames.front().wall_ms);
            std::vector<double> later, later_update;
            for (std::size_t f = 0; f < s.frames.size(); ++f) {
                const Frame& fr = s.frames[f];
                const double wall = median(fr.wall_ms);
                if (f > 0) {
                    later.push_back(wall);
                    later_update.push_back(median(fr.update_ms));
                }
                std::vector<std::string> cells{s.input, std::to_string(s.objects), s.device, std::to_string(f + 1),
                                               fmt_ms(wall), fmt_ms(median(fr.update_ms)), fmt_ms(median(fr.render_ms)),
                                               std::to_string(fr.builds),
                                               fmt_ms(median(fr.build_ms)), std::to_string(fr.compiles),
                                               fmt_ms(median(fr.compile_ms)), std::to_string(fr.upload_bytes),
                                               fmt_ms(median(fr.upload_ms))};
                csv.add(cells);
                cells.push_back(fmt_ratio(wall / first));
                t.add(cells);
            }
            const double later_ms = median(later);
            summary.add({s.input, s.device, fmt_ms(first), fmt_ms(later_ms), fmt_ms(median(later_update)),
                         fmt_ratio(later_ms / first)});
        }
        std::ostringstream md;
        md << markdown_preamble("kdrt-bench frames")
           << "One CommittedScene per input and device: Device::open(), commit() and frame 1, then the camera orbits its look-at point by "
           << fmt(opt_.step_degrees, 1) << " degrees per frame, update() and render() for frames 2 to " << opt_.frames
           << ". Wall ms: open() and commit(), or update(), plus render(), as the application waits for them; update ms: "
              "update() alone (0 for frame 1); the other columns "
              "are the frame's own work as RenderResult reports it (builds, compiles, geometry_upload_bytes and their "
              "times); frame 1 is what an application pays for every frame without a CommittedScene. Medians of "
           << opt_.runs << " sequences, each on a fresh device; the kernels are loaded from the user's kernel cache when it has them "
              "(a compile that the compiles column still counts). Trees: "
           << (opt_.intersection_cost > 0.0 ? "every device's built with SAH intersection cost " + fmt(opt_.intersection_cost, 2) +
                                                  ", the same tree on every device"
                                            : std::string("each device's own (its triangle cost)"))
           << ".\n\n"
           << summary.markdown() << "\n## Frame by frame\n\n" << t.markdown();
        write_report(opt_.out, "frames", "frames", md.str(), csv);
    }

    FramesBenchOptions opt_;
    std::vector<std::string> devices_;
    std::vector<Sequence> sequences_;
};

}  // namespace

int run_frames_bench(const FramesBenchOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    if (options.frames < 2) throw Error(ErrorCode::InvalidArgument, "--frames must be at least 2");
    machine_info();
    return FramesBench(options).run();
}

}  // namespace kdrt::bench
