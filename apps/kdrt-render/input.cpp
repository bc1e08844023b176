#include "input.h"

#include "interrupt.h"

#include "common/terminal_text.h"

#include <kdrt/model_import.h>
#include <kdrt/scene_loader.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::cli {
namespace {

using detail::escape_for_terminal;

ImportOptions import_options(const Args& a) {
    ImportOptions o;
    o.allow_outside_files = a.allow_outside_files;
    o.keep_going = [] { return !interrupted(); };
    return o;
}

void print_warnings(const std::vector<std::string>& warnings) {
    for (const std::string& w : warnings)
        std::fprintf(stderr, "kdrt-render: warning: %s\n", escape_for_terminal(w, true).c_str());
}

// --width, --height, --max-depth and --samples override the scene's own
// settings, so that a scene committed once is made for them (the OpenCL
// kernels are specialised for the depth); the frames ask for them too.
void override_settings(Scene& scene, const FrameOptions& frame) {
    if (frame.width) scene.settings.width = frame.width;
    if (frame.height) scene.settings.height = frame.height;
    if (frame.max_depth) scene.settings.max_depth = frame.max_depth;
    if (frame.samples) scene.settings.samples = frame.samples;
}

// The file as it is: a scene file, or a model with its own camera and lights.
Scene load_file(const Args& a) {
    const bool json = std::filesystem::path(a.scene_path).extension() == ".json";
    if (json || !is_model_file(a.scene_path)) {
        std::vector<std::string> warnings;
        SceneLoadOptions options{import_options(a), &warnings};
        Scene scene = load_scene(a.scene_path, options);
        print_warnings(warnings);
        return scene;
    }
    ImportStats stats;
    ModelSceneOptions options;
    options.camera = a.camera;
    options.import = import_options(a);
    Scene scene = scene_from_model(a.scene_path, options, &stats);
    print_warnings(stats.warnings);
    if (!a.quiet && (stats.skipped_points || stats.skipped_lines))
        std::fprintf(stderr, "kdrt-render: %s: skipped %zu points and %zu lines (triangles only)\n",
                     escape_for_terminal(a.scene_path).c_str(), stats.skipped_points, stats.skipped_lines);
    return scene;
}

}  // namespace

Scene load_input(const Args& a) {
    Scene scene = load_file(a);
    override_settings(scene, a.render.frame);
    return scene;
}

}  // namespace kdrt::cli
