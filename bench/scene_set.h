// The scenes a benchmark runs on: the study's five by default (in the
// study's column order), or names / paths given on the command line.
#pragma once

#include <kdrt/scene.h>

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct NamedScene {
    std::string name;              // the column title: the file's stem
    std::filesystem::path path;
    Scene scene;
};

// The study's scenes: 2x2x4, insane, purple-wall, lens, ball-o-calypse.
const std::vector<std::string>& study_scene_names();

// Where scene names are looked up: $KDRT_SCENES_DIR, else the source tree's scenes/.
std::filesystem::path default_scenes_dir();

// Loads each entry: an existing file path as is, otherwise dir/NAME.json.
// Empty `names` means the study's five. Throws kdrt::Error naming the file.
std::vector<NamedScene> load_scenes(const std::vector<std::string>& names, const std::filesystem::path& dir = {});

// Splits "a,b,c" (and repeated options) into items.
std::vector<std::string> split_list(const std::vector<std::string>& items);

}  // namespace kdrt::bench
