// The model file being imported, as the importer's parts name it: its
// extension, and errors whose message starts with its path.
#pragma once

#include <kdrt/error.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace kdrt::detail {

inline std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    if (!ext.empty() && ext.front() == '.') ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

// Throws kdrt::Error("<path>: <what>").
class ModelFailure {
public:
    explicit ModelFailure(const std::filesystem::path& path) : file_(path.string()) {}
    [[noreturn]] void operator()(const std::string& what, ErrorCode code = ErrorCode::InvalidScene) const {
        throw Error(code, file_ + ": " + what);
    }

private:
    std::string file_;
};

}  // namespace kdrt::detail
