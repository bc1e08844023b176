#include "scene_set.h"

#include <kdrt/error.h>
#include <kdrt/scene_loader.h>

#include <cstdlib>

namespace kdrt::bench {

const std::vector<std::string>& study_scene_names() {
    static const std::vector<std::string> names{"2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"};
    return names;
}

std::filesystem::path default_scenes_dir() {
    if (const char* env = std::getenv("KDRT_SCENES_DIR"); env && *env) return env;
#ifdef KDRT_BENCH_SCENES_DIR
    return KDRT_BENCH_SCENES_DIR;
#else
    return "scenes";
#endif
}

std::vector<NamedScene> load_scenes(const std::vector<std::string>& names, const std::filesystem::path& dir) {
    const std::vector<std::string>& list = names.empty() ? study_scene_names() : names;
    const std::filesystem::path base = dir.empty() ? default_scenes_dir() : dir;
    std::vector<NamedScene> out;
    for (const std::string& n : list) {
        std::filesystem::path p = n;
        if (!std::filesystem::is_regular_file(p)) p = base / (n + ".json");
        if (!std::filesystem::is_regular_file(p))
            throw Error(ErrorCode::Io, "scene '" + n + "': neither a file nor " + p.string());
        out.push_back({p.stem().string(), p, load_scene(p)});
    }
    return out;
}

std::vector<std::string> split_list(const std::vector<std::string>& items) {
    std::vector<std::string> out;
    for (const std::string& item : items) {
        std::size_t start = 0;
        while (start <= item.size()) {
            const std::size_t comma = item.find(',', start);
            const std::string part = item.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
            if (!part.empty()) out.push_back(part);
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
    }
    return out;
}

}  // namespace kdrt::bench
