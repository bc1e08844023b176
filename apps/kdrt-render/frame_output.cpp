#include "frame_output.h"

#include "frame_names.h"
#include "interrupt.h"
#include "stats_json.h"

#include "common/atomic_file.h"
#include "common/terminal_text.h"

#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/image.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

namespace kdrt::cli {
namespace {

using detail::escape_for_terminal;

// Runs a write to `file`'s temporary; its errors name the target, the file the user asked for.
template <class Write>
void naming_target(const detail::AtomicFile& file, Write&& write) {
    try {
        write();
    } catch (const Error& e) {
        std::string message = e.what();
        const std::string temporary = file.temporary().string(), target = file.target().string();
        for (std::size_t at = message.find(temporary); at != std::string::npos; at = message.find(temporary, at))
            message.replace(at, temporary.size(), target);
        throw Error(e.code(), message);
    }
}

// Writes a frame's image and id map (frame_names.h names them when there are
// several frames). Returns the milliseconds it took (--stats-json's write_ms).
double write_outputs(const Args& a, const RenderResult& r, int frame) {
    // Both files are written in full beside their targets before either
    // replaces its target, so a failing id map does not leave a new image
    // next to an old id map (or the reverse).
    const auto start = std::chrono::steady_clock::now();
    std::optional<detail::AtomicFile> image_file, ids_file;
    if (!a.output.empty()) {
        const std::string path = frame_file_name(a.output, frame, a.frames);
        image_file.emplace(path, std::filesystem::path(path).extension().string());
        naming_target(*image_file, [&] { write_image(image_file->temporary(), r.image, a.image); });
    }
    if (!a.aov_ids.empty()) {
        ids_file.emplace(frame_file_name(a.aov_ids, frame, a.frames));
        naming_target(*ids_file, [&] { write_id_map(ids_file->temporary(), r); });
    }
    stop_if_interrupted();  // the temporaries are removed as the AtomicFiles go
    if (image_file) image_file->commit();
    if (ids_file) ids_file->commit();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

double finish_frame(const Args& a, const Scene& scene, const RenderResult& r, int frame) {
    for (const std::string& w : r.warnings)
        std::fprintf(stderr, "kdrt-render: warning: %s\n", escape_for_terminal(w, true).c_str());
    const double write_ms = write_outputs(a, r, frame);
    if (a.tree_stats && !a.stats_json && frame == 0) {
        if (r.stats.tree_stats) std::cout << tree_stats_json(*r.stats.tree_stats).dump(2) << "\n";
        if (r.stats.bvh_stats) std::cout << bvh_stats_json(*r.stats.bvh_stats).dump(2) << "\n";
    }
    if (!a.stats_json && !a.quiet && !a.output.empty()) {
        const std::string output = frame_file_name(a.output, frame, a.frames);
        std::fprintf(stderr, "%s: %dx%d, %.1f ms (%.2f Mrays/s) on %s -> %s\n", escape_for_terminal(scene.name).c_str(),
                     r.image.width, r.image.height, r.stats.render_ms,
                     r.stats.render_ms > 0 ? r.stats.rays.total() / (r.stats.render_ms * 1000.0) : 0.0,
                     escape_for_terminal(r.stats.device_name).c_str(), escape_for_terminal(output).c_str());
        const double pixels = static_cast<double>(r.image.width) * r.image.height;
        for (const DeviceShare& d : r.stats.device_shares)
            std::fprintf(stderr, "  %s: %llu tiles, %.1f%% of the pixels, %.1f ms busy, %.2f Mrays\n",
                         escape_for_terminal(d.device_name).c_str(), static_cast<unsigned long long>(d.tiles),
                         pixels > 0 ? 100.0 * static_cast<double>(d.pixels) / pixels : 0.0, d.busy_ms,
                         static_cast<double>(d.rays.total()) / 1e6);
    }
    return write_ms;
}

}  // namespace kdrt::cli
