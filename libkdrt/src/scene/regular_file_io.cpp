#include "scene/regular_file_io.h"

#include <algorithm>
#include <filesystem>
#include <string_view>

namespace kdrt::detail {
namespace {

bool is_regular(const char* file) {
    std::error_code ec;
    return file != nullptr && std::filesystem::is_regular_file(file, ec);
}

}  // namespace

void RegularFileIo::note_missing(const std::string& file) const {
    if (std::find(missing_.begin(), missing_.end(), file) == missing_.end()) missing_.push_back(file);
}

bool RegularFileIo::Exists(const char* file) const {
    if (is_regular(file)) return true;
    if (file != nullptr) note_missing(file);
    return false;
}

Assimp::IOStream* RegularFileIo::Open(const char* file, const char* mode) {
    // Model files are only ever read.
    if (mode == nullptr || std::string_view(mode).find_first_of("wa+") != std::string_view::npos) return nullptr;
    if (!is_regular(file)) {
        if (file != nullptr) note_missing(file);
        return nullptr;
    }
    return Assimp::DefaultIOSystem::Open(file, mode);
}

}  // namespace kdrt::detail
