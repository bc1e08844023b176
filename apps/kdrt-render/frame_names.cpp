#include "frame_names.h"

#include <algorithm>
#include <filesystem>

namespace kdrt::cli {

std::string frame_file_name(const std::string& path, int frame, int frames) {
    if (frames <= 1 || path.empty()) return path;
    const int digits = std::max(4, static_cast<int>(std::to_string(frames - 1).size()));
    std::string number = std::to_string(frame);
    number.insert(0, static_cast<std::size_t>(std::max(0, digits - static_cast<int>(number.size()))), '0');
    const std::filesystem::path p(path);
    std::filesystem::path named = p.parent_path() / (p.stem().string() + "_" + number + p.extension().string());
    return named.string();
}

}  // namespace kdrt::cli
