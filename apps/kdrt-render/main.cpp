// kdrt-render: renders a scene file (or a model file) to an image. Exit codes
// (command_line.cpp's help footer): 0 success, 1 bad input or a failed write,
// 2 usage error, 128 + the signal's number when stopped by SIGINT, SIGTERM
// or SIGHUP (interrupt.h).
#include "allocator_tuning.h"
#include "camera_orbit.h"
#include "command_line.h"
#include "frame_output.h"
#include "input.h"
#include "interrupt.h"
#include "output_check.h"
#include "progress_bar.h"
#include "stats_json.h"

#include "common/terminal_text.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/render.h>
#include <kdrt/tiled_render.h>

#ifdef KDRT_MPI
#include "cluster/cluster_job.h"
#include "cluster/command_line_agreement.h"
#include "cluster_run.h"
#endif

#include <csignal>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace kdrt::cli;
using kdrt::detail::escape_for_terminal;

#ifdef KDRT_MPI
const kdrt::cluster::MpiSession* mpi_session = nullptr;  // set by main() under mpirun
#endif

bool mpi_session_active() {
#ifdef KDRT_MPI
    return mpi_session != nullptr;
#else
    return false;
#endif
}

// Names the rank in messages of a rank other than 0 (rank 0 names the others itself).
std::string rank_prefix() {
#ifdef KDRT_MPI
    if (mpi_session && mpi_session->rank() != 0) return mpi_session->name() + ": ";
#endif
    return {};
}

void print_devices() {
    for (const kdrt::DeviceInfo& d : kdrt::list_devices()) {
        // Driver strings are printed escaped: they are not ours.
        std::printf("%-10s %s | %s | %s | %s | driver %s | %u compute units | %.1f GiB global, %.1f GiB max alloc | fp64 %s\n",
                    escape_for_terminal(d.id).c_str(), escape_for_terminal(d.platform).c_str(),
                    escape_for_terminal(d.name).c_str(), escape_for_terminal(d.vendor).c_str(),
                    escape_for_terminal(d.type).c_str(), escape_for_terminal(d.driver_version).c_str(),
                    d.compute_units, d.global_memory / 1073741824.0,
                    d.max_allocation / 1073741824.0, d.fp64 ? "yes" : "no");
    }
}

kdrt::cli::ProgressMode progress_mode(const Args& a) {
    if (a.no_progress) return ProgressMode::Never;
    if (a.progress) return ProgressMode::Always;
    return a.quiet || a.output.empty() ? ProgressMode::Never : ProgressMode::Auto;
}

// One frame on one device or, with a device list, in tiles shared by them.
void render_one_frame(const Args& a, const kdrt::Scene& scene, const std::vector<kdrt::Device>& devices,
                      const kdrt::RenderOptions& o, ProgressBar& bar) {
    kdrt::RenderResult r = devices.size() > 1
                               ? kdrt::MultiDeviceScene::commit(devices, scene, o.commit).render(o.frame, a.tile_size)
                               : kdrt::render(scene, o);
    bar.finish();
    stop_if_interrupted();  // a library that finished its phase anyway: write nothing
    const double write_ms = finish_frame(a, scene, r, 0);
    if (a.stats_json) print_stats(a, stats_json(a, scene, o, r, a.tile_size, write_ms), 0);
}

// A camera path: the scene is committed once, each frame only moves the camera.
void render_frames(const Args& a, const kdrt::Scene& scene, const std::vector<kdrt::Device>& devices,
                   const kdrt::RenderOptions& o, ProgressBar& bar, int& frame) {
    std::optional<kdrt::MultiDeviceScene> several;
    std::optional<kdrt::CommittedScene> one;
    if (devices.size() > 1)
        several = kdrt::MultiDeviceScene::commit(devices, scene, o.commit);
    else
        one = kdrt::CommittedScene::commit(kdrt::Device::open(o.device), scene, o.commit);
    kdrt::Scene moved = scene;
    for (; frame < a.frames; ++frame) {
        moved.camera = orbit_camera(scene.camera, frame, a.frames);
        if (frame > 0) several ? several->update(moved) : one->update(moved);
        kdrt::RenderResult r = several ? several->render(o.frame, a.tile_size) : one->render(o.frame);
        stop_if_interrupted();
        if (frame == a.frames - 1) bar.finish();
        const double write_ms = finish_frame(a, moved, r, frame);
        if (a.stats_json) print_stats(a, stats_json(a, moved, o, r, a.tile_size, write_ms), frame);
    }
}

// One process: outputs checked, scene loaded, devices opened, frames rendered and written.
int render(const Args& a) {
    check_outputs(a);  // every frame's outputs, before any work
    if (!a.output.empty()) kdrt::check_image_output(a.output);
    const kdrt::Scene scene = load_input(a);
    ProgressBar bar(progress_mode(a));
    int frame = 0;
    kdrt::RenderOptions o = a.render;
    // Returning false cancels the commit or the render (kdrt::Error(Cancelled)).
    o.commit.progress = o.frame.progress = [&bar, &frame, &a](double f) {
        bar.update((frame + f) / a.frames);
        return !interrupted();
    };
    std::vector<kdrt::Device> devices;
    if (!a.devices.empty()) devices = kdrt::open_devices(o.device);
    if (devices.size() == 1) o.device = devices[0].info().id;  // "all" on a machine with one device
    stop_if_interrupted();
    if (a.frames == 1)
        render_one_frame(a, scene, devices, o, bar);
    else
        render_frames(a, scene, devices, o, bar, frame);
    return 0;
}

// The exit status of an error (under mpirun passed to every rank, so that
// mpirun's status is the same whichever rank ends first).
int exit_code_of(const std::exception_ptr& error) {
    try {
        std::rethrow_exception(error);
    } catch (const UsageError&) {
        return 2;
    } catch (const kdrt::Error& e) {
        return e.code() == kdrt::ErrorCode::Cancelled && interrupted() ? 128 + interrupt_signal() : 1;
    } catch (...) {
        return 1;
    }
}

// Prints what ended the run (rank 0 alone for a usage error under mpirun) and returns its status.
int report(const std::exception_ptr& error, bool report_usage) {
    const int code = exit_code_of(error);
    try {
        std::rethrow_exception(error);
    } catch (const UsageError& e) {
        if (report_usage)
            std::fprintf(stderr, "kdrt-render: %s\nRun with --help for more information.\n",
                         escape_for_terminal(e.what(), true).c_str());
    } catch (const kdrt::Error& e) {
        if (code > 128) {
            const int sig = interrupt_signal();
            std::fprintf(stderr, "kdrt-render: %s\n", sig == SIGTERM ? "terminated" : sig == SIGHUP ? "hung up" : "interrupted");
        } else {
            std::fprintf(stderr, "kdrt-render: %s%s\n", rank_prefix().c_str(), escape_for_terminal(e.what(), true).c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-render: %serror: %s\n", rank_prefix().c_str(), escape_for_terminal(e.what(), true).c_str());
    }
    return code;
}

// What the command line asked for, once it is agreed on (every rank under mpirun).
int run(const CommandLine& c) {
    if (c.action == CommandLine::Action::ListDevices) {
        print_devices();
        return 0;
    }
    install_interrupt_handler();
#ifdef KDRT_MPI
    if (mpi_session) return run_cluster(*mpi_session, c.args, exit_code_of);
#endif
    return render(c.args);
}

// A command line that ends the run before it starts: help, version, a usage error.
int print_exit(const std::string& message, int code, bool is_error) {
    if (is_error)
        std::fprintf(stderr, "kdrt-render: %s\nRun with --help for more information.\n",
                     escape_for_terminal(message, true).c_str());
    else
        std::fputs((message + (message.empty() || message.back() == '\n' ? "" : "\n")).c_str(), stdout);
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    tune_allocator();
#ifdef KDRT_MPI
    std::optional<kdrt::cluster::MpiSession> session;
    try {
        if (kdrt::cluster::launched_by_mpirun()) session.emplace(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-render: MPI: %s\n", e.what());
        return 1;
    }
    if (session) mpi_session = &*session;
#endif
    const CommandLine c = parse_command_line(argc, argv, mpi_session_active());
    bool report_usage = true;  // under mpirun, rank 0 alone reports what every rank would
#ifdef KDRT_MPI
    if (session) {
        const kdrt::cluster::Agreement agreed = kdrt::cluster::agree_on_command_line(
            *session, {static_cast<int>(c.action), c.exit_code, c.message});
        if (!agreed.proceed)
            return session->rank() == 0 ? print_exit(agreed.message, agreed.exit_code, agreed.message_is_error)
                                        : agreed.exit_code;
        report_usage = session->rank() == 0;
    }
#endif
    if (c.action == CommandLine::Action::Exit) return print_exit(c.message, c.exit_code, c.exit_code != 0);
    try {
        return run(c);
#ifdef KDRT_MPI
    } catch (const kdrt::cluster::JobStopped& e) {
        return e.exit_code;  // rank 0 says why
#endif
    } catch (...) {
        return report(std::current_exception(), report_usage);
    }
}
