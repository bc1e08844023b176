// OpenCL event profiling of a frame (OpenClExecution::profile_commands): what
// it reports, and that it changes nothing of the picture.
#include "have_opencl.h"
#include "opencl/cl_devices.h"

#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

using namespace kdrt;

namespace {

using kdrt_test::have_opencl;

RenderOptions options_for(Schedule schedule) {
    RenderOptions o;
    o.device = "opencl";
    o.frame.width = 48;
    o.frame.height = 40;
    o.frame.opencl.schedule = schedule;
    o.frame.want_ids = true;
    o.commit.kernel_cache_dir = kdrt_test::no_disk_kernel_cache();
    return o;
}

}  // namespace

TEST_CASE("opencl profile: every launch is timed and the picture is the unprofiled one", "[opencl][profile][slow]") {
    if (!have_opencl()) return;
    // lens: mirror and glass rays, several bounce levels; purple-wall: camera and shadow rays only.
    for (const char* name : {"lens", "purple-wall"}) {
        const Scene scene = load_scene(std::string(KDRT_SCENES_DIR) + "/" + name + ".json");
        for (Schedule schedule : {Schedule::Persistent, Schedule::Wavefront, Schedule::Plain}) {
            for (int samples : {1, 2}) {
                INFO(name << ", schedule " << to_string(schedule) << ", " << samples << " samples");
                RenderOptions o = options_for(schedule);
                o.frame.samples = samples;
                const RenderResult plain = render(scene, o);
                CHECK(plain.stats.opencl.command_times.empty());
                CHECK(plain.stats.opencl.device_busy_ms == 0.0);

                o.frame.opencl.profile_commands = true;
                const RenderResult profiled = render(scene, o);
                // Fixed-point accumulation: the same bits with or without profiling.
                CHECK(profiled.image.rgb == plain.image.rgb);
                CHECK(profiled.ids == plain.ids);
                CHECK(profiled.stats.rays.total() == plain.stats.rays.total());

                // A CPU device's persistent threads trace whole ray trees: one
                // level of launches (the camera rays'), where rays bounce.
                const bool trees = schedule == Schedule::Persistent && profiled.stats.rays.secondary > 0 &&
                                   profiled.stats.opencl.kernel_options.find("-DKDRT_CPU_DEVICE") != std::string::npos;
                const std::string trace = trees                             ? "trace_trees"
                                          : schedule == Schedule::Plain ? "trace_plain"
                                                                        : "trace_persistent";
                std::uint64_t trace_launches = 0;
                std::set<int> levels;
                std::set<std::string> commands;
                for (const CommandTime& c : profiled.stats.opencl.command_times) {
                    INFO(c.command << " level " << c.level);
                    CHECK(c.count >= 1);
                    CHECK(c.device_ms >= 0.0);
                    commands.insert(c.command);
                    if (c.command == trace) {
                        trace_launches += c.count;
                        CHECK(levels.insert(c.level).second);  // one entry per level
                    } else {
                        CHECK(c.level == 0);
                    }
                }
                CHECK(static_cast<int>(trace_launches) == profiled.stats.opencl.launches);
                // Levels 1 .. deepest, none skipped; more than one where rays bounce.
                REQUIRE(!levels.empty());
                CHECK(*levels.begin() == 1);
                CHECK(*levels.rbegin() == static_cast<int>(levels.size()));
                CHECK((levels.size() > 1) == (profiled.stats.rays.secondary > 0 && !trees));
                // One sample, where a work-item has a pixel's whole sum (its
                // ray tree, or a scene without bounces): the trace kernels
                // write the image, no accumulator to fill and resolve
                // (to_pixel, render.cl).
                const bool writes_image = samples == 1 && (trees || profiled.stats.features.max_depth == 1);
                for (const char* c : {"write counters", "read counters", "read image", "read ids"})
                    CHECK(commands.count(c) == 1);
                for (const char* c : {"fill image", "resolve image"})
                    CHECK(commands.count(c) == (writes_image ? 0u : 1u));
                CHECK(profiled.stats.opencl.device_busy_ms > 0.0);
            }
        }
    }
}
