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

}  // namespace

Scene load_input(const Args& a) {
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

}  // namespace kdrt::cli
